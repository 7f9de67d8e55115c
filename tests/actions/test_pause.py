"""Pause and resume (DESIGN §13): freeze a subtree where it stands, without unwinding it."""

from __future__ import annotations

import asyncio
import logging
import types
from collections.abc import Generator

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionState,
    EventKind,
    Outcome,
    Resource,
    Robot,
    action,
    lock,
)
from pyrobots_aio.actions import current_action
from pyrobots_aio.actions._pause import Stepped
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time

ARM = Resource("arm")


@action
async def ticker(robot: Robot, ticks: list[float], period: float = 1.0) -> None:
    while True:
        await robot.sleep(period)
        ticks.append(robot.time())


@action
async def raw_then_move(robot: Robot, log: list[str]) -> None:
    await asyncio.sleep(1)  # a raw asyncio await, not the library's
    log.append(f"moved at {robot.time():g}")


@pytest.mark.asyncio
async def test_a_paused_action_stops_where_it_stands_and_resumes_there() -> None:
    ticks: list[float] = []
    async with Robot() as robot:
        handle = ticker(robot, ticks)
        await robot.sleep(2.5)
        assert handle.pause("hold still") is True
        assert handle.paused
        assert handle.state is ActionState.PAUSED
        assert handle.pause_reason == "hold still"
        await robot.sleep(10)
        assert ticks == [1.0, 2.0]  # nothing moved while frozen
        assert handle.resume() is True
        assert not handle.paused
        assert handle.state is ActionState.RUNNING
        await robot.sleep(2)
        handle.cancel()
    # The tick due at 3.0 came 10 s late: the frozen time did not count in robot.sleep.
    assert ticks == [1.0, 2.0, 13.0, 14.0]
    assert handle.frozen_time() == 10.0


@pytest.mark.asyncio
async def test_code_after_a_raw_await_does_not_run_while_frozen() -> None:
    log: list[str] = []
    async with Robot() as robot:
        handle = raw_then_move(robot, log)
        await robot.sleep(0.5)
        handle.pause()
        await robot.sleep(5)  # the raw sleep completed meanwhile; the code after it waits
        assert log == []
        handle.resume()
        await handle
    assert log == ["moved at 5.5"]


@action
async def parent_of_two(robot: Robot, ticks: dict[str, list[float]]) -> None:
    ticker(robot, ticks["a"])
    ticker(robot, ticks["b"])
    await robot.sleep(3600)


@pytest.mark.asyncio
async def test_pausing_a_parent_freezes_its_subtree_and_a_child_paused_alone_stays_paused() -> None:
    ticks: dict[str, list[float]] = {"a": [], "b": []}
    async with Robot() as robot:
        top = parent_of_two(robot, ticks)
        await robot.sleep(1.5)
        a, b = top.children
        b.pause("on its own")
        top.pause("all of it")
        assert [h.state for h in (top, a, b)] == [ActionState.PAUSED] * 3
        await robot.sleep(5)
        top.resume()
        assert (a.paused, b.paused) == (False, True)
        await robot.sleep(1)
        b.resume()
        await robot.sleep(1)
        await robot.cancel_all()
    assert ticks["a"] == [1.0, 7.0, 8.0]  # frozen 5 s (1.5 to 6.5)
    assert ticks["b"] == [1.0, 8.0]  # frozen 6 s (1.5 to 7.5): its own pause outlasted top's


@action
async def pauses_itself_then_starts_a_child(robot: Robot, ticks: list[float]) -> None:
    me = current_action.get()
    assert me is not None
    me.pause("wait for the operator")
    ticker(robot, ticks)  # started by a frozen action: it starts frozen
    await robot.sleep(3600)


@pytest.mark.asyncio
async def test_a_child_started_by_a_frozen_action_starts_frozen() -> None:
    ticks: list[float] = []
    async with Robot() as robot:
        handle = pauses_itself_then_starts_a_child(robot, ticks)
        await robot.sleep(5)
        (child,) = handle.children
        assert child.state is ActionState.PAUSED
        assert ticks == []
        handle.resume()
        await robot.sleep(2.5)
        await robot.cancel_all()
    assert ticks == [6.0, 7.0]


@action
async def careful(robot: Robot, log: list[str]) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(1)  # the cleanup is not frozen
        log.append(f"cleaned up at {robot.time():g}")
        raise


@pytest.mark.asyncio
async def test_cancellation_reaches_a_paused_action_at_once_and_its_cleanup_runs() -> None:
    log: list[str] = []
    async with Robot() as robot:
        handle = careful(robot, log)
        await robot.sleep(1)
        handle.pause()
        await robot.sleep(5)
        handle.cancel("enough")
        assert handle.state is ActionState.CANCELLING
        assert await handle.wait_done() is Outcome.CANCELLED
    assert log == ["cleaned up at 7"]


@pytest.mark.asyncio
async def test_a_pause_leaves_the_cleanup_of_a_cancelled_descendant_running() -> None:
    log: list[str] = []
    events = EventLog()

    @action(on_pause=lambda robot: log.append("tidy paused"))
    async def tidy(robot: Robot) -> None:
        await robot.sleep(1)
        log.append(f"tidied at {robot.time():g}")

    @action
    async def arm(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await tidy(robot)  # its cleanup: it runs unfrozen
            raise

    @action
    async def task(robot: Robot) -> None:
        arm(robot)
        await robot.sleep(3600)

    async with Robot(instruments=[events]) as robot:
        top = task(robot)
        await robot.sleep(0.5)
        [child] = top.children
        child.cancel("bumper")
        await robot.sleep(0.25)
        top.pause("operator")
        [cleanup] = child.children
        assert (cleanup.paused, cleanup.frozen_time()) == (False, 0.0)
        await robot.sleep(2)
        assert log == ["tidied at 1.5"]  # the pause did not stretch the cleanup's sleep
        top.resume()
        await robot.cancel_all()
    assert [e.name for e in events.of_kind(EventKind.ACTION_PAUSED)] == ["task"]


@action
@lock(ARM)
async def hold_arm(robot: Robot, log: list[str], name: str, seconds: float) -> None:
    log.append(f"{name} got the arm at {robot.time():g}")
    await robot.sleep(seconds)


@pytest.mark.asyncio
async def test_a_paused_holder_keeps_its_resource_and_a_paused_waiter_its_place() -> None:
    log: list[str] = []
    async with Robot() as robot:
        holder = hold_arm(robot, log, "holder", 2)
        await robot.sleep(0.5)
        first = hold_arm(robot, log, "first", 1)
        second = hold_arm(robot, log, "second", 1)
        await robot.sleep(0.5)
        holder.pause()
        first.pause()  # it waits for the arm: it keeps its place in the queue
        await robot.sleep(5)
        assert robot.resources.owner(ARM) is holder
        holder.resume()
        await robot.sleep(2)  # holder done at 7 (frozen 5 s); first got the arm, frozen
        assert robot.resources.owner(ARM) is first
        assert first.state is ActionState.PAUSED
        first.resume()
        await asyncio.wait([first, second])
    assert log == [
        "holder got the arm at 0",
        "first got the arm at 8",  # granted at 7, its code ran once resumed
        "second got the arm at 9",
    ]


@pytest.mark.asyncio
async def test_pause_hooks_run_with_the_robot_and_failures_are_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    seen: list[str] = []

    async def restore(robot: Robot) -> None:
        seen.append(f"resumed at {robot.time():g}")

    def broken(robot: Robot) -> None:
        raise RuntimeError("hook broke")

    @action(on_pause=lambda robot: seen.append(f"paused at {robot.time():g}"), on_resume=restore)
    async def motor(robot: Robot) -> None:
        await robot.sleep(3600)

    @action(on_pause=broken)
    async def fragile(robot: Robot) -> None:
        await robot.sleep(3600)

    async with Robot() as robot:
        handle, other = motor(robot), fragile(robot)
        await robot.sleep(1)
        robot.pause_all("break")
        assert handle.paused
        assert other.paused
        await robot.sleep(1)
        robot.resume_all()
        await robot.sleep(0)
        await robot.cancel_all()
    assert seen == ["paused at 1", "resumed at 2"]
    (error,) = [r for r in caplog.records if r.levelno >= logging.ERROR]
    assert error.getMessage() == "pause hook of action fragile#2 failed"


@pytest.mark.asyncio
async def test_pauses_are_recorded_and_shown() -> None:
    events = EventLog()
    ticks: list[float] = []
    async with Robot(instruments=[events]) as robot:
        handle = ticker(robot, ticks)
        await robot.sleep(0.5)
        handle.pause("operator")
        assert robot.running()[0].state is ActionState.PAUSED
        assert "ticker#1 paused" in robot.action_tree()
        handle.resume()
        assert handle.resume() is False  # not paused any more
        await robot.cancel_all()
    assert handle.pause() is False  # done
    paused = events.first(EventKind.ACTION_PAUSED)
    resumed = events.first(EventKind.ACTION_RESUMED)
    assert (paused.name, paused.data["reason"], paused.data["paused"]) == ("ticker", "operator", 1)
    assert resumed.time == paused.time == 0.5


@types.coroutine
def exchange(log: list[str]) -> Generator[str, str, None]:
    log.append((yield "hello"))  # a raw yield, and the value sent back


@pytest.mark.asyncio
async def test_a_value_sent_while_frozen_reaches_the_body_when_it_thaws() -> None:
    log: list[str] = []

    async def body() -> None:
        await exchange(log)

    async with Robot() as robot:
        handle = ticker(robot, [])  # a running action: the trampoline's handle
        await robot.sleep(0)
        stepped = Stepped(handle, body())
        assert next(stepped) == "hello"
        handle.pause()
        thaw = stepped.send("world")  # frozen: kept, and the task gets the thaw future
        assert isinstance(thaw, asyncio.Future)
        assert thaw._asyncio_future_blocking
        assert stepped.send(None) is thaw  # the thaw future is done only when it thaws
        assert log == []
        handle.resume()
        with pytest.raises(StopIteration):
            stepped.send(None)  # what the task sends once the thaw future is done
        handle.cancel()
    assert log == ["world"]


@pytest.mark.asyncio
async def test_the_trampoline_passes_throw_in_every_form_and_close_to_the_body() -> None:
    log: list[str] = []

    async def body() -> None:
        try:
            await asyncio.sleep(3600)
        except KeyError as exc:
            log.append(f"caught {exc!r}")
            await asyncio.sleep(3600)
        finally:
            log.append("cleaned up")

    async with Robot() as robot:
        handle = ticker(robot, [])  # a running action: the trampoline's handle
        await robot.sleep(0)
        # What a task does and what `yield from` delegation does: an instance, a type, or
        # a type with its value and traceback.
        for throw_args in [(KeyError("a"),), (KeyError,), (KeyError, KeyError("c"), None)]:
            stepped = Stepped(handle, body())
            assert isinstance(next(stepped), asyncio.Future)
            assert isinstance(stepped.throw(*throw_args), asyncio.Future)  # caught, awaits again
            stepped.close()
        handle.cancel()
    assert log == [
        "caught KeyError('a')", "cleaned up", "caught KeyError()", "cleaned up",
        "caught KeyError('c')", "cleaned up",
    ]  # fmt: skip
