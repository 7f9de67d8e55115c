"""An anyio task group owning the robot next to the service's other tasks (virtual time)."""

from __future__ import annotations

import anyio
import anyio.abc
import pytest

from pyrobots_aio import ActionCancelled, ActionState, Outcome, Robot, action


@action
async def patrol(robot: Robot) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(0.5)  # cleanup that awaits: parking takes half a second
        robot.state.parked = True
        raise


@action
async def dock(robot: Robot) -> str:
    await robot.sleep(3600)
    return "docked"


async def robot_service(
    *, task_status: anyio.abc.TaskStatus[Robot] = anyio.TASK_STATUS_IGNORED
) -> None:
    """The robot as one task of the group: it runs until the group is cancelled."""
    async with Robot() as robot:
        robot.state.update(battery=1.0, parked=False)
        task_status.started(robot)
        await anyio.sleep_forever()


async def telemetry(robot: Robot, seen: list[float]) -> None:
    async for level in robot.watch("battery"):
        seen.append(level)  # noqa: PERF401 (kept as they come: the task may be cancelled)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_cancelling_the_group_stops_the_robot_after_its_cleanup() -> None:
    seen: list[float] = []
    async with anyio.create_task_group() as group:
        robot = await group.start(robot_service)
        group.start_soon(telemetry, robot, seen)
        walk = patrol(robot)
        owned, watched = dock(robot), dock(robot)
        with anyio.move_on_after(1):
            await owned  # owning: the deadline cancels the action
        with anyio.move_on_after(1):
            await watched.wait_done()  # not owning: the deadline leaves it running
        assert (owned.outcome, owned.cancel_reason) == (
            Outcome.CANCELLED,
            "the task awaiting it was cancelled",
        )
        assert watched.state is ActionState.RUNNING
        for level in (0.9, 0.8):
            robot.state.battery = level
            await anyio.sleep(1)
        group.cancel_scope.cancel()  # the robot, the telemetry: every task of the group
    assert anyio.current_time() == 4.5  # the robot waited for the patrol's cleanup
    assert not robot.is_running
    assert robot.state.parked
    for handle in (walk, watched):
        assert (handle.outcome, handle.cancel_reason) == (Outcome.CANCELLED, "robot shutting down")
    assert seen == [0.9, 0.8]


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_watch_in_the_group_ends_by_itself_when_the_robot_stops() -> None:
    seen: list[float] = []
    stop = anyio.Event()

    async def robot_until_stopped(
        *, task_status: anyio.abc.TaskStatus[Robot] = anyio.TASK_STATUS_IGNORED
    ) -> None:
        async with Robot() as robot:
            robot.state.battery = 1.0
            task_status.started(robot)
            await stop.wait()

    with anyio.fail_after(60):  # a watch that never ended would hang the group
        async with anyio.create_task_group() as group:
            robot = await group.start(robot_until_stopped)
            group.start_soon(telemetry, robot, seen)
            await anyio.sleep(1)
            robot.state.battery = 0.7
            robot.state.battery = 0.6
            await anyio.sleep(1)
            stop.set()  # nothing is cancelled: the robot stops, the watch ends, the group ends
    assert seen == [0.7, 0.6]
    assert anyio.current_time() == 2.0
