"""Handles among asyncio's tools: done-callbacks, wait/gather/as_completed, owning waits."""

from __future__ import annotations

import asyncio
import logging

import pytest

from pyrobots_aio import (
    ActionHandle,
    ActionInterrupted,
    Outcome,
    Robot,
    action,
)

pytestmark = pytest.mark.virtual_time


@action
async def nap(robot: Robot, seconds: float, value: int = 0) -> int:
    await robot.sleep(seconds)
    return value


@action
async def fail_after(robot: Robot, seconds: float) -> None:
    await robot.sleep(seconds)
    raise ValueError("servo unplugged")


@action
async def parent_of(robot: Robot, children: list[ActionHandle[int]]) -> str:
    children.append(nap(robot, 1.0))
    await children[-1]
    return "parent done"


def _boom(handle: ActionHandle[object]) -> None:
    raise RuntimeError(f"callback broke on {handle.name}")


@pytest.mark.asyncio
async def test_done_callbacks_receive_the_handle_soon_after_it_is_done() -> None:
    seen: list[tuple[str, Outcome]] = []
    async with Robot() as robot:
        handle = nap(robot, 0.5, 7)
        handle.add_done_callback(lambda h: seen.append((h.name, h.outcome)))
        assert await handle == 7
        assert seen == [("nap", Outcome.SUCCEEDED)]  # before the awaiter resumed
        handle.add_done_callback(lambda h: seen.append(("late", h.outcome)))
        assert seen == [("nap", Outcome.SUCCEEDED)]  # scheduled, not called in place
        await asyncio.sleep(0)
        assert seen[-1] == ("late", Outcome.SUCCEEDED)


@pytest.mark.asyncio
async def test_on_done_calls_in_place_before_the_done_callbacks_and_at_once_once_done() -> None:
    # The library's own hook (monitors count the actions their callbacks start with it).
    seen: list[str] = []
    async with Robot() as robot:
        handle = nap(robot, 0.5)
        handle.add_done_callback(lambda h: seen.append("done-callback"))
        handle.on_done(lambda h: seen.append(f"on_done {h.outcome.value}"))
        await handle
        assert seen == ["on_done succeeded", "done-callback"]
        handle.on_done(lambda h: seen.append("late"))  # was never called: it waited for an end
        assert seen[-1] == "late"


@pytest.mark.asyncio
async def test_remove_done_callback_counts_what_it_removed() -> None:
    seen: list[str] = []

    def note(h: ActionHandle[int]) -> None:
        seen.append(h.name)

    async with Robot() as robot:
        handle = nap(robot, 0.5)
        handle.add_done_callback(note)
        handle.add_done_callback(note)
        assert handle.remove_done_callback(note) == 2
        assert handle.remove_done_callback(note) == 0
        await handle
        await asyncio.sleep(0)
    assert seen == []


@pytest.mark.asyncio
async def test_a_raising_done_callback_hangs_nothing(caplog: pytest.LogCaptureFixture) -> None:
    children: list[ActionHandle[int]] = []
    async with asyncio.timeout(60):
        async with Robot() as robot:
            top = parent_of(robot, children)
            await robot.sleep(0.1)
            (child,) = children
            child.add_done_callback(_boom)
            sleeper = nap(robot, 3600)
            sleeper.add_done_callback(_boom)
            assert await top == "parent done"  # the parent waiting for that child finishes
            await robot.cancel_all("stop")  # returns
            assert sleeper.outcome is Outcome.CANCELLED
            last = nap(robot, 3600)
            last.add_done_callback(_boom)
        # ... and leaving the robot did not hang either
    errors = [r for r in caplog.records if r.levelno == logging.ERROR]
    assert [r.getMessage().split(" of action ")[1] for r in errors] == [
        "nap#2 failed",
        "nap#3 failed",
        "nap#4 failed",
    ]
    assert all(isinstance(r.exc_info[1], RuntimeError) for r in errors if r.exc_info)


@pytest.mark.asyncio
async def test_asyncio_wait_works_over_handles() -> None:
    async with Robot() as robot:
        fast, slow = nap(robot, 1.0, 1), nap(robot, 5.0, 5)
        done, pending = await asyncio.wait([fast, slow], return_when=asyncio.FIRST_COMPLETED)
        assert done == {fast}
        assert pending == {slow}
        assert robot.time() == 1.0
        done, pending = await asyncio.wait([slow], timeout=1.0)
        assert (done, pending) == (set(), {slow})
        assert not slow.cancel_requested  # asyncio.wait owns nothing
        broken = fail_after(robot, 0.5)
        done, _ = await asyncio.wait([slow, broken], return_when=asyncio.FIRST_EXCEPTION)
        assert done == {broken}
        done, _ = await asyncio.wait([slow])
        assert done == {slow}
        assert slow.result() == 5


@pytest.mark.asyncio
async def test_asyncio_gather_works_over_handles() -> None:
    async with Robot() as robot:
        assert await asyncio.gather(nap(robot, 2.0, 2), nap(robot, 1.0, 1)) == [2, 1]
        cancelled = nap(robot, 10)
        cancelled.cancel("no")
        results = await asyncio.gather(nap(robot, 1.0, 1), cancelled, return_exceptions=True)
        assert results[0] == 1
        assert isinstance(results[1], ActionInterrupted)
        with pytest.raises(ValueError, match="servo unplugged"):
            await asyncio.gather(fail_after(robot, 0.5), nap(robot, 0.1))


@pytest.mark.asyncio
async def test_asyncio_as_completed_works_over_handles() -> None:
    async with Robot() as robot:
        handles = [nap(robot, float(s), s) for s in (3, 1, 2)]
        assert [await next_one for next_one in asyncio.as_completed(handles)] == [1, 2, 3]
        assert robot.time() == 3.0


@action
async def until(robot: Robot, gate: asyncio.Future[None]) -> int:
    await gate
    return 1


@pytest.mark.asyncio
async def test_every_waiter_wakes_but_one_that_gave_up() -> None:
    async with Robot() as robot:
        handle = nap(robot, 2.0, 7)
        first = asyncio.create_task(handle.wait())
        second = asyncio.create_task(handle.wait_done())
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(1):
                await handle.wait_done()  # the third gives up: the two others still wait
        assert (await first, await second) == (7, Outcome.SUCCEEDED)


@pytest.mark.asyncio
async def test_an_awaiter_cancelled_as_the_action_ends_is_woken_once() -> None:
    async with Robot() as robot:
        gate: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        handle = until(robot, gate)
        awaiter = asyncio.create_task(handle.wait())
        await asyncio.sleep(0)
        gate.set_result(None)  # the body's step is queued first,
        awaiter.cancel()  # the awaiter's wake-up second: the action ends in between
        with pytest.raises(asyncio.CancelledError):
            await awaiter
        assert await handle == 1  # it ended as it would have; its end woke nobody twice
        assert not handle.cancel_requested


@pytest.mark.asyncio
async def test_await_owns_the_action_but_wait_done_does_not() -> None:
    async with Robot() as robot:
        owned = nap(robot, 10)
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(1):
                await owned
        assert await owned.wait_done() is Outcome.CANCELLED
        assert owned.cancel_reason == "the task awaiting it was cancelled"

        watched = nap(robot, 10, 10)
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(1):
                await watched.wait_done()
        assert not watched.cancel_requested  # a long-poll that gave up left it running
        assert await watched == 10
