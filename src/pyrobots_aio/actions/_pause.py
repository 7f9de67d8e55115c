"""Pause and resume: freeze an action's subtree where it stands, without unwinding it.

An action is *frozen* while it or one of its ancestors is paused and no
cancellation was requested for it (cancellation reaches a paused action at
once, and its cleanup must run). Its body runs through `Stepped`, which
forwards each ``send``/``throw`` of the task to the body: whatever the body
awaits (``robot.sleep``, a raw ``asyncio.sleep``, a socket) may complete
meanwhile, but the body is not resumed until the action thaws. So a body
frozen after ``await asyncio.sleep(5)`` does not reach the ``robot.drive(...)``
that follows it.

Each handle counts the time it spent frozen, so that `Robot.sleep` does not
count it. Pause hooks (``@action(on_pause=..., on_resume=...)``) are called
with the robot when the action freezes and thaws: motion actions stop the
wheels there. A robot that never pauses pays one counter test per resumption.
"""

from __future__ import annotations

import asyncio
import inspect
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from ._phases import DONE

if TYPE_CHECKING:
    from collections.abc import Coroutine, Iterator

    from ._handle import ActionHandle

T = TypeVar("T")


def frozen(handle: ActionHandle[Any]) -> bool:
    """Whether ``handle`` is paused or suspended, or under such an ancestor, and not cancelled.

    A suspension (``@lock(..., preempt="suspend")`` lending the holder's
    resource to a preemptor) freezes as a pause does, apart from any pause:
    ``resume()`` lifts the pause only, and the end of the loan the suspension.

    The walk up stops at a cancelled action: cancellation reaches a paused
    action at once, and its cleanup (the actions it starts then) runs unfrozen.
    """
    node: ActionHandle[Any] | None = handle
    while node is not None:
        if node._cancel_requested:
            return False
        if node._paused or node._suspended is not None:
            return True
        node = node.parent
    return False


def frozen_time(handle: ActionHandle[Any]) -> float:
    """Seconds (loop time) ``handle`` has spent frozen so far, the current spell included."""
    since = handle._frozen_since
    if since is None:
        return handle._frozen_total
    return handle._frozen_total + handle._loop.time() - since


def subtree(handle: ActionHandle[Any]) -> Iterator[ActionHandle[Any]]:
    """``handle`` and its descendants as they are now, parents before children."""
    stack = [handle]
    while stack:
        node = stack.pop()
        yield node
        stack.extend(reversed(node._children))


class Stepped(Generic[T]):
    """The body ``coro``, awaited through this: each resumption held while ``handle`` is frozen.

    An iterator that the action's task awaits in the body's place: it forwards
    each ``send``/``throw`` to the body, unless the action is frozen. Then it
    keeps the value meant for the body and hands the task the action's thaw
    future; when that completes, the kept value goes on to the body. An
    exception thrown in (cancellation) goes on to the body at once, frozen or
    not. A class, not a generator: no frame of its own in the body's
    tracebacks, and it compiles to a native iterator.
    """

    __slots__ = ("_coro", "_executive", "_handle", "_held", "_thawing")

    def __init__(self, handle: ActionHandle[Any], coro: Coroutine[Any, Any, T]) -> None:
        self._handle = handle
        self._executive = handle._executive
        self._coro = coro
        self._held: Any = None  # the value the body gets when it thaws
        self._thawing = False  # the task waits for the thaw future

    def __await__(self) -> Stepped[T]:
        return self

    def __iter__(self) -> Stepped[T]:
        return self

    def __next__(self) -> Any:
        if self._thawing or (self._executive.paused and frozen(self._handle)):
            return self.send(None)
        return self._coro.send(None)

    def send(self, value: Any) -> Any:
        """Resume the body with ``value``, or hand the task the thaw future while it is frozen."""
        if self._thawing:  # the thaw future is done: the kept value, once the action thaws
            value = self._held
        handle = self._handle
        if self._executive.paused and frozen(handle):
            self._held = value
            self._thawing = True
            thaw = handle._thaw
            if thaw is None or thaw.done():
                thaw = handle._thaw = handle._loop.create_future()
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


def freeze(
    handle: ActionHandle[Any], reason: str | None, by: ActionHandle[Any] | None
) -> list[ActionHandle[Any]]:
    """Pause ``handle``; return the actions that froze because of it (deepest first)."""
    handle._paused = True
    handle._pause_reason = reason
    handle._paused_by = by
    return freeze_subtree(handle)


def freeze_subtree(handle: ActionHandle[Any]) -> list[ActionHandle[Any]]:
    """Start the frozen clock of ``handle``'s subtree; return what froze now (deepest first)."""
    now = handle._loop.time()
    newly = []
    for node in subtree(handle):
        if node._frozen_since is None and not node._cancel_requested and node._phase != DONE:
            node._frozen_since = now
            newly.append(node)
    newly.reverse()
    return newly


def thaw(handle: ActionHandle[Any]) -> list[ActionHandle[Any]]:
    """Resume ``handle`` (counted unpaused already); return what thawed, parents first."""
    handle._pause_reason = None
    handle._paused_by = None
    return thaw_subtree(handle)


def thaw_subtree(handle: ActionHandle[Any]) -> list[ActionHandle[Any]]:
    """Wake what in ``handle``'s subtree is no longer frozen; return it, parents first."""
    thawed = []
    for node in subtree(handle):
        if node._frozen_since is not None and not frozen(node):
            stop_frozen_clock(node)
            thawed.append(node)
    return thawed


def stop_frozen_clock(node: ActionHandle[Any]) -> None:
    """Add the spell that ends now to ``node``'s frozen time, and wake its body."""
    since = node._frozen_since
    if since is not None:
        node._frozen_total += node._loop.time() - since
        node._frozen_since = None
    if node._thaw is not None and not node._thaw.done():
        node._thaw.set_result(None)


def run_hooks(nodes: list[ActionHandle[Any]], which: int, what: str) -> None:
    """Call each node's pause (``which`` 0) or resume (1) hook with its robot; log failures."""
    for node in nodes:
        hooks = node._hooks
        hook = None if hooks is None else hooks[which]
        if hook is None:
            continue
        try:
            result = hook(node._executive.owner)
        except Exception:
            node._executive.log.exception(
                "%s hook of action %s#%d failed", what, node.name, node.id
            )
            continue
        if inspect.isawaitable(result):
            _follow(node, what, asyncio.ensure_future(result, loop=node._loop))


def _follow(node: ActionHandle[Any], what: str, task: asyncio.Future[Any]) -> None:
    """Log the failure of an async hook (it runs on its own; nothing waits for it)."""

    def done(fut: asyncio.Future[Any]) -> None:
        if not fut.cancelled() and fut.exception() is not None:
            node._executive.log.error(
                "%s hook of action %s#%d failed",
                what,
                node.name,
                node.id,
                exc_info=fut.exception(),
            )

    task.add_done_callback(done)
