"""Suspend instead of cancel, on real bases: the preempted drive ends at its goal after the reflex.

On the MuJoCo simulated robot and on `FakeBase`, in virtual time: a
``preempt="suspend"`` reflex freezes ``drive_distance(1.0)`` halfway (its
pause hook parks the wheels), turns the robot away and back, and the drive
then goes on with its remaining distance and stops within 1 cm of its goal.
The random walk's ``on_bump="suspend"`` option is driven with injected bumps.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import ActionState, EventKind, Outcome, action, lock
from pyrobots_aio.motion import WHEELS, DriveBase
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk
from pyrobots_aio.testing import EventLog, FakeBase, inject_bump

if TYPE_CHECKING:
    from collections.abc import Callable

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

BASES: dict[str, Callable[..., DriveBase]] = {"fake": FakeBase, "sim": SimRobot}


def truth(robot: DriveBase) -> tuple[float, float, float]:
    pose: tuple[float, float, float] = robot.world.base_pose()  # type: ignore[attr-defined]
    return pose


@action
@lock(WHEELS, priority=10, preempt="suspend")
async def look_away(robot: DriveBase) -> None:
    """A reflex that moves the wheels but leaves the base where it was: turn away and back."""
    await robot.rotate_angle(1.2)
    await robot.rotate_angle(-1.2)


@pytest.mark.parametrize("kind", sorted(BASES))
async def test_a_suspended_drive_ends_within_1_cm_of_its_goal_after_the_reflex(kind: str) -> None:
    async with BASES[kind]() as robot:
        await robot.undock()
        x0, y0, yaw0 = truth(robot)
        drive = robot.drive_distance(1.0)
        while math.hypot(truth(robot)[0] - x0, truth(robot)[1] - y0) < 0.5:
            await robot.sleep(robot.control_period)
        reflex = look_away(robot)
        await robot.sleep(0)
        assert drive.state is ActionState.PAUSED
        assert robot.resources.owner(WHEELS) is reflex
        await robot.sleep(0.5)
        turned = truth(robot)[2] - yaw0
        assert abs(turned) > 0.1  # the reflex drives the wheels while the drive is frozen
        assert await reflex.wait_done() is Outcome.SUCCEEDED
        assert not drive.done()
        done = await drive
        x, y, _ = truth(robot)
    assert done == pytest.approx(1.0, abs=0.003)
    goal = (x0 + math.cos(yaw0), y0 + math.sin(yaw0))
    assert math.hypot(x - goal[0], y - goal[1]) < 0.01  # within 1 cm of its goal
    assert drive.outcome is Outcome.SUCCEEDED  # never cancelled


@pytest.mark.parametrize(
    ("name", "nth", "lender"),
    [
        ("drive_distance", 2, "drive_distance"),
        ("rotate_angle", 1, "rotate_angle"),
        ("navigate_to", 1, "dock"),  # the outermost holder in the way: dock, which navigates
    ],
)
async def test_the_walk_with_a_suspending_reflex_interrupts_no_move(
    name: str, nth: int, lender: str
) -> None:
    log = EventLog()
    async with FakeBase(instruments=[log]) as robot:
        with inject_bump(robot, name, nth=nth, at="start") as bump:
            report = await random_walk(robot, moves=3, seed=0, on_bump="suspend")
        assert bump.done
        assert robot.handles() == []
    assert (report.moves, report.interrupted, report.docked) == (3, 0, True)
    assert report.bumps >= 1
    assert set(log.outcomes("suspending_reflex")) == {"succeeded"}
    assert set(log.outcomes(name)) == {"succeeded"}  # suspended, not cancelled
    (preempted, *_) = [e for e in log.events if e.kind is EventKind.RESOURCE_PREEMPTED]
    assert preempted.data["suspended"] is True
    assert preempted.name == lender


async def test_the_walk_refuses_an_unknown_on_bump() -> None:
    async with FakeBase() as robot:
        with pytest.raises(ValueError, match="on_bump must be 'cancel' or 'suspend', got 'stop'"):
            await random_walk(robot, on_bump="stop")  # type: ignore[arg-type]


async def test_the_simulated_walk_with_a_suspending_reflex_bumps_and_docks() -> None:
    log = EventLog()
    async with SimRobot(instruments=[log]) as robot:
        report = await random_walk(robot, moves=10, seed=0, on_bump="suspend")
    assert (report.moves, report.interrupted, report.docked) == (10, 0, True)
    assert report.bumps >= 1  # it ran into a wall (seed 0 does, twice)
    suspended = [e for e in log.events if e.kind is EventKind.RESOURCE_PREEMPTED]
    assert len(suspended) == report.bumps
    assert all(e.data["suspended"] for e in suspended)
    for name in ("drive_distance", "rotate_angle", "suspending_reflex"):
        assert set(log.outcomes(name)) == {"succeeded"}
