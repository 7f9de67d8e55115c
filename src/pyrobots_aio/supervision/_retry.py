"""``retry``: run an action again when it fails, after an exponential backoff.

Each attempt is a child action (so each shows in recordings and the
timeline, with its own outcome); the retrying action waits the backoff delay
between attempts. Cancellation is never retried: not the retrying action's
own (it simply ends), nor an attempt's (preempted: awaiting it raises
`ActionInterrupted`, which is re-raised at once). The one exception is an
attempt cancelled by its own `timeout`, which counts as a ``TimeoutError``.

Nor is the emergency stop: the retrying action hands itself to each stop
called while it runs (a `StopWatch`), which cancels it with its attempt, in
its backoff too; an attempt's `EmergencyStopError` is never retried, and while
the stop is latched a failed attempt is the last.
"""

from __future__ import annotations

import asyncio
import inspect
import math
import random
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._exceptions import ActionInterrupted, EmergencyStopError
from ..actions import Action, current_action
from ..actions._decorator import executive_of
from ._stop import StopWatch
from ._timeout import timed_out
from ._wrap import ActionDecorator

if TYPE_CHECKING:
    from collections.abc import Iterator


@dataclass(frozen=True, slots=True)
class Backoff:
    """How long to wait before each retry: exponential, capped, with seeded jitter.

    Made by `exponential`. Before retry ``n`` (0 for the first) the delay is
    ``min(max, base * factor**n)``, then shortened at random by up to the
    fraction ``jitter`` of it (0: exact; 1: anywhere between 0 and the delay,
    "full jitter"), so a delay never exceeds ``max``. The random draws come
    from ``random.Random(seed)``, anew for each run of the retried action: a
    seed makes them the same every run (tests), None draws fresh ones.

    Examples:
        >>> list(exponential(0.1, factor=2, max=1.0).delays(6))
        [0.1, 0.2, 0.4, 0.8, 1.0, 1.0]
        >>> [round(d, 3) for d in exponential(1.0, jitter=0.5, seed=7).delays(3)]
        [0.838, 1.849, 2.698]
    """

    base: float = 0.1
    factor: float = 2.0
    max: float = 10.0
    jitter: float = 0.0
    seed: int | None = None

    def __post_init__(self) -> None:
        for name, low in (("base", 0.0), ("factor", 1.0), ("max", self.base)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                msg = f"backoff {name} must be a number, got {value!r}"
                raise ValueError(msg)
            if not low <= value < math.inf:
                msg = f"backoff {name} must be finite and at least {low!r}, got {value!r}"
                raise ValueError(msg)
        if isinstance(self.jitter, bool) or not 0 <= self.jitter <= 1:
            msg = f"backoff jitter must be a fraction from 0 to 1, got {self.jitter!r}"
            raise ValueError(msg)
        seed = self.seed
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
            msg = f"backoff seed must be an int or None, got {self.seed!r}"
            raise ValueError(msg)

    def delays(self, count: int) -> Iterator[float]:
        """The ``count`` delays of one run, in seconds (one random generator for them all)."""
        rng = random.Random(self.seed)  # spreading retries, not cryptography
        delay = float(self.base)
        for _ in range(count):
            yield delay * (1 - self.jitter * rng.random()) if self.jitter else delay
            delay = min(self.max, delay * self.factor)


def exponential(
    base: float = 0.1,
    factor: float = 2.0,
    max: float = 10.0,  # DESIGN's name, shadowing the builtin here only
    jitter: float = 0.0,
    *,
    seed: int | None = None,
) -> Backoff:
    """Exponential backoff: ``base`` seconds, times ``factor`` each retry, at most ``max``.

    Args:
        base: Seconds before the first retry.
        factor: Each delay is the previous one times this (at least 1).
        max: The cap on a delay.
        jitter: The fraction of each delay drawn at random (0 to 1): a delay
            ``d`` becomes a random value in ``[d * (1 - jitter), d]``.
        seed: The seed of the jitter's random draws (None: fresh each run).

    Raises:
        ValueError: A value out of range (the message names it).

    Examples:
        >>> exponential(0.5, factor=3, max=4.0)
        Backoff(base=0.5, factor=3, max=4.0, jitter=0.0, seed=None)
    """
    return Backoff(base, factor, max, jitter, seed)


class retry(ActionDecorator):  # lower case: a decorator, as DESIGN names it
    """Run the action up to ``attempts`` times, waiting a `Backoff` between failures.

    Each attempt is a child action of the retrying one, which has the same
    name, parameters and result type; put it above ``@action``, or call it on
    an action: ``await retry(3)(robot.lift)()``. An attempt that raises one of
    ``on`` is retried after the next delay of ``backoff`` (logged at INFO on
    ``pyrobots_aio.supervision``); the last attempt's error is the action's.
    Cancellation is never retried: if the retrying action is cancelled, its
    attempt is too and it ends CANCELLED; an attempt cancelled from elsewhere
    (preempted) ends the retrying action at once with its `ActionInterrupted`.
    An attempt cancelled by its own `timeout` counts as a ``TimeoutError``,
    retried if ``on`` names it (or a base class of it).

    Nor is the emergency stop, whatever ``on`` says: ``robot.emergency_stop``
    cancels the retrying action (reason ``"emergency stop: <reason>"``, by
    the ``emergency_stop`` action), attempt and backoff alike, so it ends
    CANCELLED at once and awaiting it raises `ActionInterrupted`, as for every
    action the stop ends. An attempt's `EmergencyStopError` is never retried,
    and while the stop is latched a failed attempt is the last (its error is
    the action's).

    Args:
        attempts: How many times to run it, at most (1: no retry).
        backoff: The delays between attempts; default ``exponential()``
            (0.1 s, doubling, at most 10 s).
        on: The exception types that are retried (``Exception`` subclasses).

    Raises:
        ValueError: ``attempts`` is not a positive int, or ``on`` names no
            ``Exception`` subclass (cancellation is never retried).

    Examples:
        >>> from pyrobots_aio import Robot, action
        >>> from pyrobots_aio.sim import run
        >>> @retry(3, backoff=exponential(0.5), on=(ConnectionError,))
        ... @action
        ... async def connect(robot: Robot) -> float:
        ...     robot.state.tries = robot.state.get("tries", 0) + 1
        ...     if robot.state.tries < 3:
        ...         raise ConnectionError("no answer")
        ...     return robot.time()
        >>> async def main() -> float:
        ...     async with Robot() as robot:
        ...         return await connect(robot)
        >>> run(main)  # failed at 0, retried at 0.5, failed, retried at 1.5
        1.5
    """

    def __init__(
        self,
        attempts: int,
        backoff: Backoff | None = None,
        on: type[Exception] | tuple[type[Exception], ...] = (Exception,),
    ) -> None:
        if isinstance(attempts, bool) or not isinstance(attempts, int) or attempts < 1:
            msg = f"retry() attempts must be a positive int, got {attempts!r}"
            raise ValueError(msg)
        self.attempts = attempts
        self.backoff = _backoff(backoff)
        self.on = _exception_types(on)

    def apply(self, act: Action[Any, Any, Any]) -> Action[Any, Any, Any]:
        """The retrying action around ``act`` (same name, parameters and result)."""
        attempts, backoff, retries, name = self.attempts, self.backoff, self._retries, act.name

        async def retrying(robot: Any, /, *args: Any, **kwargs: Any) -> Any:
            with StopWatch(robot, current_action.get()):  # a stop cancels us, backoff included
                for attempt, delay in enumerate(backoff.delays(attempts - 1), 1):
                    try:
                        return await act(robot, *args, **kwargs)
                    except Exception as error:
                        tried = f"{attempt} of {attempts}"
                        if not retries(error) or not _log_retry(robot, name, tried, error, delay):
                            raise
                    await asyncio.sleep(delay)
                return await act(robot, *args, **kwargs)  # the last attempt: its error is ours

        retrying.__name__ = retrying.__qualname__ = name
        retrying.__doc__ = act.fn.__doc__
        retrying.__signature__ = inspect.signature(act.fn)  # type: ignore[attr-defined]
        return Action(retrying)

    def _retries(self, error: Exception) -> bool:
        """Whether an attempt that raised ``error`` is run again (but for a latched stop)."""
        if isinstance(error, EmergencyStopError):
            return False
        if timed_out(error):
            return issubclass(TimeoutError, self.on)
        return not isinstance(error, ActionInterrupted) and isinstance(error, self.on)

    def __repr__(self) -> str:
        names = ", ".join(t.__name__ for t in self.on)
        return f"retry({self.attempts}, backoff={self.backoff!r}, on=({names},))"


def _backoff(backoff: object) -> Backoff:
    if backoff is None:
        return Backoff()
    if not isinstance(backoff, Backoff):
        msg = f"retry() backoff must be a Backoff, e.g. exponential(0.1), got {backoff!r}"
        raise ValueError(msg)
    return backoff


def _exception_types(on: object) -> tuple[type[Exception], ...]:
    types = on if isinstance(on, tuple) else (on,)
    if not types or not all(isinstance(t, type) and issubclass(t, Exception) for t in types):
        msg = (
            f"retry() on= takes Exception subclasses, got {on!r}; cancellation "
            "(ActionCancelled, a BaseException) is never retried"
        )
        raise ValueError(msg)
    return types


def _log_retry(robot: Any, name: str, attempt: str, error: Exception, delay: float) -> bool:
    """Log a failed attempt that ``on`` retries; return False if the latched stop forbids it."""
    log = executive_of(robot, name).log_scope.logger("pyrobots_aio.supervision")
    stopped = robot.emergency_stop_reason
    if stopped is None:
        log.info("%s: attempt %s failed (%r); retrying in %.3g s", name, attempt, error, delay)
        return True
    log.info(
        "%s: attempt %s failed (%r); not retried: the emergency stop is latched (%r)",
        name, attempt, error, stopped,
    )  # fmt: skip
    return False
