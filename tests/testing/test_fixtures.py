from __future__ import annotations

import pytest

from pyrobots_aio import EventKind, Robot, action, lock
from pyrobots_aio.loops import is_virtual
from pyrobots_aio.sim import WHEELS, SimRobot
from pyrobots_aio.testing import EventLog


@action
async def nap(robot: Robot) -> str:
    await robot.sleep(3600)
    return "rested"


@action
@lock(WHEELS, priority=5, preempt=True)
async def grab_wheels(robot: SimRobot) -> None:
    await robot.sleep(0.1)


@pytest.mark.asyncio
async def test_robot_fixture_is_a_running_dummy_robot(robot: Robot, robot_events: EventLog) -> None:
    assert robot.is_running
    assert robot.dummy
    handle = nap(robot)
    handle.cancel("wake up")
    await handle.wait_done()
    assert robot_events.names_started() == ["nap"]
    assert robot_events.outcomes("nap") == ["cancelled"]
    robot_events.assert_cancelled("nap")


@pytest.mark.asyncio
async def test_sim_robot_fixture_runs_in_virtual_time_unmarked(
    sim_robot: SimRobot, robot_events: EventLog
) -> None:
    assert is_virtual()
    assert sim_robot.state.docked
    await sim_robot.undock()
    drive = sim_robot.drive_distance(1.0)
    await sim_robot.sleep(1.0)
    grabbed_at = sim_robot.time()
    await grab_wheels(sim_robot)
    await drive.wait_done()
    event = robot_events.assert_cancelled(
        "drive_distance", by="grab_wheels", after=grabbed_at, within=0.2
    )
    assert event.data["reason"] == "preempted by grab_wheels#4 (priority 5) for 'wheels'"
    with pytest.raises(AssertionError, match=r"'drive_distance' was not cancelled by 'nap'"):
        robot_events.assert_cancelled("drive_distance", by="nap")
    assert robot_events.first(EventKind.RESOURCE_PREEMPTED).time == pytest.approx(grabbed_at)
