"""Pause and resume: freeze an action's subtree where it stands, without unwinding it.

An action is *frozen* while it or one of its ancestors is paused and no
cancellation was requested for it (cancellation reaches a paused action at
once, and its cleanup must run). Its body runs through `stepped`, which
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
import types
from typing import TYPE_CHECKING, Any, TypeVar

from ._phases import DONE

if TYPE_CHECKING:
    from collections.abc import Coroutine, Generator, Iterator

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


@types.coroutine
def stepped(handle: ActionHandle[Any], coro: Coroutine[Any, Any, T]) -> Generator[Any, Any, T]:
    """Run ``coro`` (the body), holding each resumption while ``handle`` is frozen."""
    executive = handle._executive
    send = coro.send
    message: Any = None
    error: BaseException | None = None
    while True:
        if executive.paused and error is None and frozen(handle):
            try:
                yield from _thawed(handle)
            except GeneratorExit:
                coro.close()
                raise
            except BaseException as exc:  # cancellation reaches a frozen body at once
                error = _passed_on(exc)
        try:
            yielded = send(message) if error is None else coro.throw(error)
        except StopIteration as stop:
            return stop.value  # type: ignore[no-any-return]
        message = error = None
        try:
            message = yield yielded
        except GeneratorExit:
            coro.close()
            raise
        except BaseException as exc:  # handed on to the body, as an await would
            error = _passed_on(exc)


def _passed_on(error: BaseException) -> BaseException:
    """``error``, thrown in here by the task, without this frame in its traceback.

    The task throws a failed future's exception in (rather than sending); it
    goes on into the body as if the body had received it itself: this frame,
    which holds the handle, must not stay in its traceback.
    """
    tb = error.__traceback__
    if tb is not None and tb.tb_frame.f_code is _STEPPED:
        error.__traceback__ = tb.tb_next
    return error


def _thawed(handle: ActionHandle[Any]) -> Generator[Any, Any, None]:
    """Wait (inside `stepped`) until ``handle`` thaws."""
    while frozen(handle):
        if handle._thaw is None or handle._thaw.done():
            handle._thaw = handle._loop.create_future()
        yield from handle._thaw


_STEPPED = stepped.__code__


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
