from __future__ import annotations

import asyncio

import anyio
import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionDefinitionError,
    ActionInterrupted,
    ActionState,
    Outcome,
    Robot,
    RobotNotRunningError,
    action,
)

pytestmark = pytest.mark.virtual_time


@action
async def double(robot: Robot, x: int) -> int:
    await robot.sleep(0.5)
    return 2 * x


@action
async def fail(robot: Robot, message: str) -> None:
    await robot.sleep(0.1)
    raise ValueError(message)


@action
async def forever(robot: Robot) -> None:
    await robot.sleep(3600)


def test_action_cancelled_is_asyncio_cancelled_error() -> None:
    assert ActionCancelled is asyncio.CancelledError


@pytest.mark.asyncio
async def test_calling_an_action_schedules_it_and_returns_a_handle() -> None:
    async with Robot() as robot:
        handle = double(robot, 21)
        assert handle.name == "double"
        assert handle.state is ActionState.PENDING
        assert not handle.done()
        assert handle.outcome is Outcome.NOT_DONE
        await asyncio.sleep(0)
        assert handle.state is ActionState.RUNNING
        assert await handle == 42
        assert await handle.wait() == 42
        assert handle.result() == 42
        assert handle.exception() is None
        assert handle.outcome is Outcome.SUCCEEDED
        assert handle.done()
        assert not handle.cancelled()


@pytest.mark.asyncio
async def test_handle_ids_are_unique_and_increasing() -> None:
    async with Robot() as robot:
        handles = [double(robot, i) for i in range(5)]
        assert [h.id for h in handles] == sorted({h.id for h in handles})
        assert [await h for h in handles] == [0, 2, 4, 6, 8]


@pytest.mark.asyncio
async def test_result_before_done_raises_invalid_state() -> None:
    async with Robot() as robot:
        handle = double(robot, 1)
        with pytest.raises(asyncio.InvalidStateError, match=r"action double#1 is not done yet"):
            handle.result()
        with pytest.raises(asyncio.InvalidStateError):
            handle.exception()
        await handle


@pytest.mark.asyncio
async def test_awaiting_a_failed_action_reraises_its_exception() -> None:
    async with Robot() as robot:
        handle = fail(robot, "motor stalled")
        with pytest.raises(ValueError, match="motor stalled"):
            await handle
        assert handle.outcome is Outcome.FAILED
        assert isinstance(handle.exception(), ValueError)
        assert await handle.wait_done() is Outcome.FAILED


@pytest.mark.asyncio
async def test_cancel_returns_false_once_done() -> None:
    async with Robot() as robot:
        handle = double(robot, 1)
        await handle
        assert handle.cancel("too late") is False
        assert handle.outcome is Outcome.SUCCEEDED


@pytest.mark.asyncio
async def test_awaiting_a_cancelled_action_raises_action_interrupted() -> None:
    async with Robot() as robot:
        handle = forever(robot)
        await robot.sleep(1)
        assert handle.cancel("enough") is True
        with pytest.raises(ActionInterrupted) as caught:
            await handle
        assert str(caught.value) == f"action forever#{handle.id} was cancelled: enough"
        assert caught.value.reason == "enough"
        assert caught.value.by is None
        assert caught.value.handle is handle
        assert not isinstance(caught.value, asyncio.CancelledError)
        assert handle.cancelled()
        assert handle.outcome is Outcome.CANCELLED


@pytest.mark.asyncio
async def test_cancelling_a_pending_action_never_runs_its_body() -> None:
    ran = []

    @action
    async def note(robot: Robot) -> None:
        ran.append(True)

    async with Robot() as robot:
        handle = note(robot)
        handle.cancel("changed my mind")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert ran == []


@pytest.mark.asyncio
async def test_swallowed_cancellation_is_still_cancelled() -> None:
    @action
    async def stubborn(robot: Robot) -> str:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            return "ignored"
        return "finished"

    async with Robot() as robot:
        handle = stubborn(robot)
        await robot.sleep(0.1)
        handle.cancel()
        assert await handle.wait_done() is Outcome.CANCELLED
        with pytest.raises(ActionInterrupted):
            handle.result()


@pytest.mark.asyncio
async def test_cancel_from_an_action_records_who_cancelled() -> None:
    async with Robot() as robot:
        victim = forever(robot)

        @action
        async def reflex(robot: Robot) -> None:
            victim.cancel("bumper pressed")

        killer = reflex(robot)
        await killer
        with pytest.raises(ActionInterrupted) as caught:
            await victim
        assert caught.value.by is killer
        assert str(caught.value) == (
            f"action forever#{victim.id} was cancelled by reflex#{killer.id}: bumper pressed"
        )


@pytest.mark.asyncio
async def test_cancelling_the_awaiting_task_cancels_the_action() -> None:
    async with Robot() as robot:
        handle = forever(robot)
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(1.0):
                await handle
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.cancel_reason == "the task awaiting it was cancelled"


@pytest.mark.asyncio
async def test_starting_an_action_without_a_running_robot_says_so() -> None:
    robot = Robot()
    with pytest.raises(RobotNotRunningError) as caught:
        double(robot, 1)
    assert str(caught.value) == (
        "cannot start action 'double': <Robot stopped> is not running; "
        "start it inside 'async with robot:'"
    )


def test_starting_an_action_with_no_loop_at_all_says_so() -> None:
    with pytest.raises(RobotNotRunningError, match="is not running"):
        double(Robot(), 1)


def test_first_argument_must_be_a_robot() -> None:
    with pytest.raises(ActionDefinitionError) as caught:
        double(3, 1)  # type: ignore[arg-type]
    assert str(caught.value) == (
        "action 'double' needs the robot as its first argument, got 3; "
        "call it as double(robot, ...) or robot.double(...)"
    )


def test_action_needs_an_async_def() -> None:
    def not_async(robot: Robot) -> None:
        return None

    with pytest.raises(ActionDefinitionError, match=r"@action needs an 'async def' function"):
        action(not_async)  # type: ignore[arg-type]


@pytest.mark.asyncio
async def test_works_inside_an_application_with_its_own_tasks() -> None:
    ticks = []

    async def service() -> None:
        for i in range(5):
            ticks.append(i)
            await asyncio.sleep(0.1)

    app_task = asyncio.create_task(service())
    async with Robot() as robot:
        assert await double(robot, 2) == 4
    await app_task
    assert ticks == [0, 1, 2, 3, 4]


def test_runs_under_asyncio_run_and_anyio_run() -> None:
    async def main() -> int:
        async with Robot() as robot:
            return await double(robot, 4)

    assert asyncio.run(main()) == 8
    assert anyio.run(main, backend="asyncio") == 8
