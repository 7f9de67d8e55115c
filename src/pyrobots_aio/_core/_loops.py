"""Which loop, thread and async library the caller is on; clear errors when it is the wrong one.

A robot belongs to the asyncio loop that runs ``async with robot``. Starting an
action, writing its state, creating a monitor or awaiting a handle from
another thread, another event loop or trio fails here with an `EventLoopError`
that names the way in from there, instead of a silent misbehaviour (an action
that starts only when the loop next wakes) or asyncio's "attached to a
different loop".
"""

from __future__ import annotations

import asyncio
import sys
import threading
import time
from threading import get_ident
from typing import TYPE_CHECKING

from .._exceptions import EventLoopError

if TYPE_CHECKING:
    from collections.abc import Callable

current_loop = asyncio._get_running_loop
"""The event loop running in this thread, or None.

On Linux each call costs a ``getpid`` system call (Python 3.11 checks the
process against a fork); the hot paths test `running_here` instead.
"""


def running_here(loop: asyncio.AbstractEventLoop, thread: int) -> bool:
    """Whether ``loop``, which runs in the thread of ident ``thread``, is the caller's loop.

    The same answer as ``current_loop() is loop`` (one loop at most runs in a
    thread, and code in that thread runs inside it), for a fifth of its cost.
    The actions' hot paths inline this test.
    """
    return get_ident() == thread and loop.is_running()


def clock_of(loop: asyncio.AbstractEventLoop) -> Callable[[], float]:
    """``loop.time``, or the clock it reads (``time.monotonic``) when it is asyncio's own.

    Readings are the same; the direct clock saves a Python call on every
    timestamp of an action or a state write.
    """
    if getattr(loop.time, "__func__", None) is asyncio.BaseEventLoop.time:
        return time.monotonic
    return loop.time


def makes_plain_tasks(loop: asyncio.AbstractEventLoop) -> bool:
    """Whether ``loop.create_task(coro, name=n)`` is ``asyncio.Task(coro, loop=loop, name=n)``.

    It is when the method is asyncio's own and no task factory is set. Then a
    hot path may make the task itself, without the two Python calls of
    ``create_task`` (and its ``_check_closed``). Asked when the robot starts:
    a task factory must be set before.
    """
    own = getattr(loop.create_task, "__func__", None) is asyncio.BaseEventLoop.create_task
    return own and loop.get_task_factory() is None


THREADSAFE_HINT = (
    "from another thread, use robot.call_soon_threadsafe(fn, *args) or "
    "robot.run_threadsafe(coro) (asyncio.run_coroutine_threadsafe), or "
    "anyio.from_thread.run(...) from an anyio worker thread"
)
TRIO_HINT = 'pyrobots_aio needs asyncio; use anyio.run(..., backend="asyncio")'


def under_trio() -> bool:
    """Whether the caller runs inside trio (checked without importing trio)."""
    trio = sys.modules.get("trio")
    if trio is None:
        return False
    try:
        trio.lowlevel.current_task()
    except RuntimeError:
        return False
    return True


def no_asyncio_loop(what: str) -> EventLoopError:
    """The error for ``what`` attempted where no asyncio loop runs (trio, or plain sync code)."""
    if under_trio():
        return EventLoopError(f"cannot {what} under trio: {TRIO_HINT}")
    return EventLoopError(
        f"cannot {what}: no asyncio event loop is running in thread "
        f"{threading.current_thread().name!r}; run it under asyncio.run(...)"
    )


def wrong_loop(what: str, loop: asyncio.AbstractEventLoop, thread: str) -> EventLoopError:
    """The error for ``what`` attempted off ``loop`` (which runs in thread ``thread``)."""
    here = threading.current_thread().name
    running = current_loop()
    if running is None and under_trio():
        return EventLoopError(f"cannot {what} under trio: {TRIO_HINT}")
    if running is None or here != thread:
        return EventLoopError(
            f"cannot {what} from thread {here!r}: the robot runs on the event loop of "
            f"thread {thread!r}; {THREADSAFE_HINT}"
        )
    return EventLoopError(
        f"cannot {what} from another event loop ({running!r}): the robot runs on {loop!r}; "
        "use one loop for the robot and its users, or hand work over with "
        "robot.run_threadsafe(coro)"
    )
