"""Code that never awaits: which action blocks the loop, and running such code off it.

The loop watchdog (`pyrobots_aio._core._blockwatch`) asks `blocking_action`
which action runs the task on a blocked loop; `run_off_loop` is
``robot.to_thread``.
"""

from __future__ import annotations

import asyncio
import contextvars
from typing import TYPE_CHECKING, Any, TypeVar, TypeVarTuple

from .._core._blockwatch import Blocker

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from .._core._logging import ScopedLogger
    from ..actions import ActionHandle

T = TypeVar("T")
Ts = TypeVarTuple("Ts")


def blocking_action(
    handles: Iterable[ActionHandle[Any]], task: asyncio.Task[object] | None
) -> Blocker | None:
    """The action whose task is ``task`` (the one running on the blocked loop), if any.

    Called from the watchdog's thread while the loop is blocked: it only reads.
    """
    if task is None:
        return None
    for handle in handles:
        if handle._task is task:
            body = getattr(handle._coro, "cr_frame", None)  # where to look for the culprit line
            return Blocker(f"action {handle.name}#{handle.id}", handle.id, handle.name, body)
    return None


async def run_off_loop(
    loop: asyncio.AbstractEventLoop, log: ScopedLogger, fn: Callable[[*Ts], T], *args: *Ts
) -> T:
    """Run ``fn(*args)`` in the loop's default executor; give up waiting when cancelled.

    The call runs in a copy of the caller's context. A cancelled caller stops
    waiting at once; the call goes on in its thread, its result is dropped, and
    an exception it raises later is logged with its traceback on ``log``.
    """
    call = contextvars.copy_context().run
    future = loop.run_in_executor(None, call, fn, *args)
    try:
        return await asyncio.shield(future)
    except asyncio.CancelledError:
        future.add_done_callback(lambda done: _late(done, log, fn))
        raise


def _late(future: asyncio.Future[Any], log: ScopedLogger, fn: Callable[..., object]) -> None:
    """Log what the abandoned call of ``fn`` raised, if it raised."""
    if future.cancelled():
        return
    error = future.exception()
    if error is not None:
        name = getattr(fn, "__qualname__", repr(fn))
        log.error(
            "robot.to_thread(%s) raised after its caller was cancelled (its result is dropped)",
            name,
            exc_info=error,
        )
