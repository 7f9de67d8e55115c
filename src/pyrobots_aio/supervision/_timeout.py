"""``timeout(seconds)``: a deadline the caller puts on an action.

STYLE's "callers own deadlines": actions take no ``timeout=`` parameter; a
caller wraps the action instead. The action itself is cancelled when its
deadline passes (counted from the start of its body, waiting for resources
included), so it ends CANCELLED, its cleanup runs, and awaiting it raises
`ActionInterrupted` whose reason is a `TimeoutReason`: "timeout after 2 s".
"""

from __future__ import annotations

import asyncio
import contextvars
import functools
from typing import TYPE_CHECKING, Any

from .._core._numbers import finite
from .._exceptions import ActionDefinitionError, ActionInterrupted
from ..actions import Action, current_action
from ._wrap import ActionDecorator

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine


class TimeoutReason(str):
    """The cancel reason of an action whose `timeout` expired: ``"timeout after N s"``.

    A string (recordings and messages show it as one) that also says, by its
    type, that a deadline cancelled the action, not a preemption or a user.

    Attributes:
        seconds: The deadline that expired.

    Examples:
        >>> reason = TimeoutReason(2.0)
        >>> reason, reason.seconds
        ('timeout after 2 s', 2.0)
    """

    seconds: float

    def __new__(cls, seconds: float) -> TimeoutReason:
        reason = super().__new__(cls, f"timeout after {seconds:g} s")
        reason.seconds = seconds
        return reason


def timed_out(error: BaseException) -> bool:
    """Whether ``error`` is the `ActionInterrupted` of an action that its `timeout` cancelled.

    Examples:
        >>> timed_out(ValueError("no"))
        False
    """
    return isinstance(error, ActionInterrupted) and isinstance(error.reason, TimeoutReason)


def check_seconds(name: str, value: object) -> float:
    """Return ``value`` as a float, or raise `ValueError` unless it is a positive finite number."""
    return finite(name, value, positive=True, must="a positive number of seconds")


class timeout(ActionDecorator):  # lower case: a decorator, as DESIGN names it
    """Cancel the action if it has not finished ``seconds`` after it started.

    The action ends CANCELLED with the reason ``"timeout after N s"`` (a
    `TimeoutReason`); its cleanup runs as for any cancellation, and awaiting
    it raises `ActionInterrupted`. It keeps its name, parameters and result
    type. Put it above ``@action``, or call it on an action: ``await
    timeout(2)(robot.lift)()``. Inside `retry`, an attempt that times out
    counts as a ``TimeoutError`` for ``on=``. An action that another
    cancellation reached first (an emergency stop, a preemption) keeps its
    reason, even if its cleanup outlasts the deadline: it never reads as
    timed out.

    Raises:
        ValueError: ``seconds`` is not a positive number.

    Examples:
        >>> from pyrobots_aio import ActionCancelled, ActionInterrupted, Robot, action
        >>> from pyrobots_aio.sim import run
        >>> @timeout(2)
        ... @action
        ... async def wave(robot: Robot) -> None:
        ...     try:
        ...         await robot.sleep(60)
        ...     except ActionCancelled:
        ...         robot.state.arm = "lowered"  # the cleanup runs
        ...         raise
        >>> async def main() -> tuple[str | None, str, float]:
        ...     async with Robot() as robot:
        ...         try:
        ...             await wave(robot)
        ...         except ActionInterrupted as error:
        ...             return error.reason, robot.state.arm, robot.time()
        ...     return None, "", 0.0
        >>> reason, arm, when = run(main)
        >>> reason, arm, round(when, 6)
        ('timeout after 2 s', 'lowered', 2.0)
    """

    def __init__(self, seconds: float) -> None:
        self.seconds = check_seconds("timeout", seconds)

    def apply(self, act: Action[Any, Any, Any]) -> Action[Any, Any, Any]:
        """The action ``act`` with this deadline (same name, parameters and result)."""
        return Action(_with_deadline(act.fn, self.seconds))

    def __repr__(self) -> str:
        return f"timeout({self.seconds:g})"


def _with_deadline(
    fn: Callable[..., Coroutine[Any, Any, Any]], seconds: float
) -> Callable[..., Coroutine[Any, Any, Any]]:
    """``fn`` as an action body that cancels its action after ``seconds``."""
    name = getattr(fn, "__name__", repr(fn))

    @functools.wraps(fn)  # keeps __wrapped__: a @lock below still holds until the action is done
    async def timed(*args: Any, **kwargs: Any) -> Any:
        handle = current_action.get()
        if handle is None:
            msg = f"timeout on {name!r} runs as an action body; start it as {name}(robot, ...)"
            raise ActionDefinitionError(msg)
        loop = asyncio.get_running_loop()
        # An empty context: the cancellation comes from no action (`by` is None), not from itself.
        expiry = loop.call_later(
            seconds, handle.cancel, TimeoutReason(seconds), context=contextvars.Context()
        )
        try:
            return await fn(*args, **kwargs)
        finally:
            expiry.cancel()

    return timed
