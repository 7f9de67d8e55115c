"""The shielded wait of every shutdown path: held cancellations, no spinning under anyio."""

from __future__ import annotations

import asyncio
import time

import anyio
import pytest

from pyrobots_aio import ActionCancelled, Robot, action
from pyrobots_aio._core._waiting import Countdown, wait_shielded


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_native_cancel_is_held_until_the_wait_is_over() -> None:
    loop = asyncio.get_running_loop()
    fut: asyncio.Future[None] = loop.create_future()
    loop.call_later(5, fut.set_result, None)
    task = asyncio.create_task(wait_shielded(fut))
    await asyncio.sleep(1)
    task.cancel("stop")
    await asyncio.sleep(1)
    assert not task.done()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert loop.time() == 5.0
    assert fut.result() is None  # never cancelled itself


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_deadline_ends_the_wait() -> None:
    loop = asyncio.get_running_loop()
    fut: asyncio.Future[None] = loop.create_future()
    assert await wait_shielded(fut, deadline=loop.time() + 3) is False
    assert loop.time() == 3.0
    assert not fut.done()
    countdown = Countdown(loop, 0)
    assert await wait_shielded(countdown.future) is True


@action
async def linger(robot: Robot, seconds: float) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await asyncio.sleep(seconds)  # a slow cleanup, in real time
        raise


CLEANUP = 0.3  # real seconds of cleanup during which the shutdown waits


@pytest.mark.asyncio
async def test_shutdown_under_an_anyio_cancel_scope_waits_without_spinning() -> None:
    """anyio re-delivers a scope's cancellation every iteration: a naive wait spins a core."""

    async def callback() -> None:
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            await asyncio.sleep(CLEANUP)
            raise

    robot = Robot()
    cpu = time.process_time()
    with anyio.move_on_after(0.05):
        async with robot:
            robot.state.bumper = False
            robot.whenever("bumper", becomes=True).do(callback)
            robot.state.bumper = True
            linger(robot, CLEANUP)
            await anyio.sleep(3600)  # the scope's deadline lands here: leaving runs the shutdown
    used = time.process_time() - cpu
    assert not robot.is_running
    assert robot.handles() == []
    assert robot.events.monitors() == []
    # The shutdown waited ~2 x CLEANUP of wall time; spinning would burn about as much CPU.
    assert used < CLEANUP / 3, f"{used:.3f} CPU-s for {2 * CLEANUP} s of waiting"
