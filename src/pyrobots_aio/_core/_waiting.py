"""Waiting for things to end: the one shielded wait every shutdown path uses.

Shutting down must finish its (bounded) wait even when the task doing it is
cancelled meanwhile, by asyncio (``Task.cancel``, ``asyncio.timeout``, Ctrl-C
under ``asyncio.run``) or by an anyio cancel scope. anyio re-delivers a
scope's cancellation at every loop iteration, so a wait that catches
``CancelledError`` and waits again spins a core; `wait_shielded` instead sits
in a shielded anyio scope, lets a native cancellation through only once, and
re-raises it when the wait is over. What bounds the wait is the caller's: a
deadline, or timers (the executive's watchdog) that make the waited-for
future done.
"""

from __future__ import annotations

import asyncio
from typing import Any

# anyio imports its asyncio backend on first use: the first cancel scope, which is the
# robot's exit, on the loop. That import takes 0.1-0.2 s, a stall of every cleanup that the
# loop watchdog reports; importing it with the library moves it off the loop.
import anyio
import anyio._backends._asyncio

from ._numbers import finite


class Countdown:
    """A future done once `tick` has been called ``count`` times (at once if ``count`` is 0).

    Examples:
        >>> async def main() -> bool:
        ...     countdown = Countdown(asyncio.get_running_loop(), 2)
        ...     countdown.tick()
        ...     countdown.tick()
        ...     return countdown.future.done()
        >>> asyncio.run(main())
        True
    """

    __slots__ = ("_left", "future")

    def __init__(self, loop: asyncio.AbstractEventLoop, count: int) -> None:
        self.future: asyncio.Future[None] = loop.create_future()
        self._left = count
        if count <= 0:
            self.future.set_result(None)

    def tick(self, *_: object) -> None:
        """Count one thing done (any arguments are ignored, so it fits done-callbacks)."""
        self._left -= 1
        if self._left <= 0 and not self.future.done():
            self.future.set_result(None)


async def wait_shielded(waiter: asyncio.Future[Any], deadline: float | None = None) -> bool:
    """Wait until ``waiter`` is done or the loop's clock reaches ``deadline``, whatever happens.

    A cancellation of the calling task (asyncio's or an anyio scope's) does not
    cut the wait short and costs no busy loop: it is held, and re-raised once
    the wait is over. ``waiter`` itself is never cancelled.

    Returns:
        True if ``waiter`` is done, False if the deadline passed first.

    Examples:
        >>> async def main() -> bool:
        ...     loop = asyncio.get_running_loop()
        ...     fut = loop.create_future()
        ...     loop.call_later(0.01, fut.set_result, None)
        ...     return await wait_shielded(fut, deadline=loop.time() + 10)
        >>> asyncio.run(main())
        True
    """
    loop = asyncio.get_running_loop()
    gate = loop.create_future()

    def opened(*_: object) -> None:
        if not gate.done():
            gate.set_result(None)

    waiter.add_done_callback(opened)
    timer = loop.call_at(deadline, opened) if deadline is not None else None
    interrupted: BaseException | None = None
    try:
        while not gate.done():
            try:
                with anyio.CancelScope(shield=True):
                    await asyncio.shield(gate)
            except asyncio.CancelledError as exc:  # held; re-raised once the wait is over
                interrupted = exc
    finally:
        waiter.remove_done_callback(opened)
        if timer is not None:
            timer.cancel()
    if interrupted is not None:
        raise interrupted
    return waiter.done()


async def sleep_until(deadline: float) -> None:
    """Sleep until the loop's clock reads ``deadline`` (at once if it already does).

    Unlike ``asyncio.sleep(deadline - now)``, the timer is set at ``deadline``
    itself, so a virtual-time loop wakes exactly there: no float residue left
    to sleep on.

    Examples:
        >>> from pyrobots_aio.sim import run
        >>> async def main() -> float:
        ...     await sleep_until(1.2)
        ...     return asyncio.get_running_loop().time()
        >>> run(main)
        1.2
    """
    deadline = finite("deadline", deadline)  # a NaN in the loop's timer heap breaks its order
    loop = asyncio.get_running_loop()
    fut = loop.create_future()
    timer = loop.call_at(deadline, _set_unless_done, fut)
    try:
        await fut
    finally:
        timer.cancel()


def _set_unless_done(fut: asyncio.Future[None]) -> None:
    if not fut.done():
        fut.set_result(None)
