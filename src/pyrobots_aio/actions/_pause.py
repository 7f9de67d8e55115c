"""Pause and resume: freeze an action's subtree where it stands, without unwinding it.

An action is *frozen* while it or one of its ancestors is paused (or
suspended, its resource lent) and no cancellation was requested on the way
(cancellation reaches a paused action at once, and its cleanup must run).
Its body runs through `Stepped`, which forwards each ``send``/``throw`` of the
task to the body: whatever the body awaits (``robot.sleep``, a raw
``asyncio.sleep``, a socket) may complete meanwhile, but the body is not
resumed until the action thaws. So a body frozen after ``await
asyncio.sleep(5)`` does not reach the ``robot.drive(...)`` that follows it.

The handle keeps what pausing needs in a `Freeze`, made the first time the
action freezes (most never do): why it is paused or suspended, the frozen
clock (so that `Robot.sleep` does not count frozen time) and the thaw future
its task waits on. The handle walks its subtree and writes these through the
`Freeze` methods; an action that never froze pays one ``is None`` test per
resumption. Pause hooks (``@action(on_pause=..., on_resume=...)``) are called
with the robot when the action freezes and thaws: motion actions stop the
wheels there. `Stepped` and `run_hooks` read the handle's freeze, loop and
hooks themselves: they are the handle's own machinery, apart only to keep
``_handle.py`` readable, and write nothing of it.
"""

from __future__ import annotations

import asyncio
import enum
import inspect
from typing import TYPE_CHECKING, Any, Generic, TypeVar

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Generator

    from .._core._logging import ScopedLogger
    from ._handle import ActionHandle

T = TypeVar("T")


class Freeze:
    """An action's pause, its suspension and its frozen clock (owned by its handle).

    A *spell* is a stretch of time the action spends frozen, from the moment
    it or an ancestor freezes until it thaws or is cancelled: ``since`` is set
    during one, and ``total`` adds up those that ended.
    """

    __slots__ = ("by", "paused", "reason", "since", "suspended", "thaw", "total")

    def __init__(self) -> None:
        self.paused = False
        """Paused itself (`ActionHandle.pause`), until `ActionHandle.resume`."""
        self.reason: str | None = None
        """The reason given to the pause."""
        self.by: object = None
        """The action that paused it, or None."""
        self.suspended: str | None = None
        """The reason of the suspension lending its resources to a preemptor, if any."""
        self.since: float | None = None
        """Loop time when the current spell began, or None if it is not frozen."""
        self.total = 0.0
        """Seconds frozen in the spells that ended."""
        self.thaw: asyncio.Future[None] | None = None
        """What the action's task waits on while frozen; done when the spell ends."""

    @property
    def holds(self) -> bool:
        """Whether this action itself freezes its subtree: paused or suspended."""
        return self.paused or self.suspended is not None

    def pause(self, reason: str | None, by: object) -> None:
        """Record a pause (a second one replaces the reason)."""
        self.paused, self.reason, self.by = True, reason, by

    def unpause(self) -> None:
        """Forget the pause."""
        self.paused, self.reason, self.by = False, None, None

    def suspend(self, reason: str) -> None:
        """Record a suspension (a second one replaces the reason)."""
        self.suspended = reason

    def unsuspend(self) -> None:
        """Forget the suspension."""
        self.suspended = None

    def begin(self, now: float) -> bool:
        """Start a spell at ``now`` unless one runs; return whether it started."""
        if self.since is not None:
            return False
        self.since = now
        return True

    def end(self, now: float) -> None:
        """End the spell at ``now`` (if one runs) and wake the task waiting for the thaw."""
        if self.since is not None:
            self.total += now - self.since
            self.since = None
        thaw = self.thaw
        if thaw is not None and not thaw.done():
            thaw.set_result(None)

    def spent(self, now: float) -> float:
        """Seconds frozen so far, the current spell included."""
        return self.total if self.since is None else self.total + now - self.since

    def waiter(self, loop: asyncio.AbstractEventLoop) -> asyncio.Future[None]:
        """The thaw future of the current spell (made once for it)."""
        thaw = self.thaw
        if thaw is None or thaw.done():
            thaw = self.thaw = loop.create_future()
        return thaw


Hooks = tuple["Callable[[Any], object] | None", "Callable[[Any], object] | None"]
"""An action's pause and resume hooks, each called with the robot (or None)."""


_NOTHING = object()
_YIELDED = object()
"""`Stepped._thawing` when the body's first yield is still to be passed to the task."""


class Stepped(Generic[T]):
    """The body ``coro``, awaited through this: each resumption held while ``handle`` is frozen.

    An iterator that the action's task awaits in the body's place: it forwards
    each ``send``/``throw`` to the body, unless the action is frozen. Given
    ``yielded``, the body has run its first step already (the action's task
    runs it unwrapped, as most bodies end there) and that is what it awaits. Then it
    keeps the value meant for the body and hands the task the action's thaw
    future; when that completes, the kept value goes on to the body. An
    exception thrown in (cancellation) goes on to the body at once, frozen or
    not. A class, not a generator: no frame of its own in the body's
    tracebacks.
    """

    __slots__ = ("_coro", "_handle", "_held", "_thawing")

    def __init__(
        self, handle: ActionHandle[T], coro: Coroutine[Any, Any, T], yielded: Any = _NOTHING
    ) -> None:
        self._handle = handle
        self._coro = coro
        if yielded is _NOTHING:
            self._held: Any = None  # the value the body gets when it thaws
            self._thawing: object = False  # the task waits for the thaw future
        else:  # the body was stepped once already: what it yielded goes to the task first
            self._held = yielded
            self._thawing = _YIELDED

    def __await__(self) -> Generator[Any, Any, T]:
        return self  # an iterator with send and throw, as a generator

    def __iter__(self) -> Stepped[T]:
        return self

    def __next__(self) -> Any:
        if self._thawing or self._handle._freeze is not None:
            return self.send(None)
        return self._coro.send(None)

    def send(self, value: Any) -> Any:
        """Resume the body with ``value``, or hand the task the thaw future while it is frozen."""
        if self._thawing:
            if self._thawing is _YIELDED:  # not a resumption: the body's first yield, passed on
                yielded, self._held, self._thawing = self._held, None, False
                return yielded
            value = self._held  # the thaw future is done: the kept value, once it thaws
        handle = self._handle
        freeze = handle._freeze
        if freeze is not None and freeze.since is not None:
            self._held = value
            self._thawing = True
            thaw = freeze.waiter(handle._loop)
            thaw._asyncio_future_blocking = True  # what ``yield from thaw`` would set
            return thaw
        self._thawing = False
        self._held = None
        return self._coro.send(value)

    def throw(self, kind: Any, value: Any = None, traceback: Any = None) -> Any:
        """Throw an exception into the body at once, frozen or not (cancellation must arrive)."""
        if isinstance(kind, BaseException):
            error = kind
        elif isinstance(value, BaseException):
            error = value
        else:
            error = kind() if value is None else kind(value)
        if traceback is not None:
            error = error.with_traceback(traceback)
        self._thawing = False
        self._held = None
        return self._coro.throw(error)

    def close(self) -> None:
        """Close the body (the task's coroutine is closed while it waits here)."""
        self._thawing = False
        self._held = None
        self._coro.close()


class Hook(enum.Enum):
    """Which of an action's hooks to call (``@action(on_pause=..., on_resume=...)``)."""

    PAUSE = "pause"
    RESUME = "resume"


def run_hooks(nodes: list[ActionHandle[Any]], hook: Hook, robot: object, log: ScopedLogger) -> None:
    """Call each node's ``hook`` with ``robot``; log what fails (an async hook runs on its own)."""
    index = 0 if hook is Hook.PAUSE else 1
    for node in nodes:
        hooks = node._hooks
        call = None if hooks is None else hooks[index]
        if call is None:
            continue
        try:
            result = call(robot)
        except Exception:
            log.exception("%s hook of action %s#%d failed", hook.value, node.name, node.id)
            continue
        if inspect.isawaitable(result):
            _follow(node, hook, asyncio.ensure_future(result, loop=node._loop), log)


def _follow(
    node: ActionHandle[Any], hook: Hook, task: asyncio.Future[Any], log: ScopedLogger
) -> None:
    """Log the failure of an async hook (it runs on its own; nothing waits for it)."""

    def done(fut: asyncio.Future[Any]) -> None:
        if not fut.cancelled() and fut.exception() is not None:
            log.error(
                "%s hook of action %s#%d failed",
                hook.value,
                node.name,
                node.id,
                exc_info=fut.exception(),
            )

    task.add_done_callback(done)
