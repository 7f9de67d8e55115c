"""A bump at any moment of the random walk: the reflex acts, the walk goes on, and docks.

The Create 3 script's bug class (DESIGN §1): its reflex cancelled the current
goal and control never came back. Here a bump is injected at every action
boundary of a three-move walk (seed 0: no bump of its own on any base), on
the left, the right and both bumpers, with the reflex cancelling or
suspending the motion it preempts, in virtual time, on every base.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Literal

import pytest

from pyrobots_aio import EventKind, Outcome
from pyrobots_aio.sim.random_walk import bumper_reflex, random_walk, suspending_reflex
from pyrobots_aio.testing import EventLog, inject_bump

if TYPE_CHECKING:
    from .conftest import Base

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

Boundary = tuple[str, int, Literal["start", "end"]]
# Seed 0, three moves: undock (its own drive_distance #1), drive out (#2), then three
# moves (rotate_angle #k, drive_distance #k+2), then dock (its navigate_to, then reversing:
# a bump at navigate_to's end comes as the dock starts reversing onto it, issue 23).
BOUNDARIES: list[Boundary] = [
    *((name, nth, at) for name, count in [("undock", 1), ("drive_distance", 5),
        ("rotate_angle", 3), ("navigate_to", 1)] for nth in range(1, count + 1)
        for at in ("start", "end")),
    ("dock", 1, "start"),
]  # fmt: skip


REFLEXES = {"cancel": bumper_reflex.name, "suspend": suspending_reflex.name}
REVERSE_SPEED = 0.05  # m/s: how fast the dock reverses onto it


@pytest.mark.parametrize("side", ["left", "right", "both"])
@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
@pytest.mark.parametrize("boundary", BOUNDARIES, ids=lambda b: f"{b[0]}{b[1]}-{b[2]}")
async def test_a_bump_at_any_boundary_is_handled_and_the_walk_docks(
    base: Base,
    boundary: Boundary,
    on_bump: Literal["cancel", "suspend"],
    side: Literal["left", "right", "both"],
) -> None:
    name, nth, at = boundary
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        with inject_bump(robot, name, nth=nth, at=at, side=side) as bump:
            report = await random_walk(robot, moves=3, seed=0, on_bump=on_bump)
        assert bump.done
        assert robot.state.docked
        assert not robot.state.bumper
        assert robot.handles() == []
    assert report.moves == 3  # control came back to the walk
    assert report.docked
    assert report.bumps >= 1  # the injected one, and any its detour ran into
    if on_bump == "suspend":
        assert report.interrupted == 0
    reflex = log.first(EventKind.ACTION_STARTED, REFLEXES[on_bump])
    assert bump.time is not None
    assert reflex.time == pytest.approx(bump.time)  # the reflex ran at once ...
    assert set(log.outcomes(REFLEXES[on_bump])) == {"succeeded"}  # ... and to its end
    assert log.outcomes("dock")[-1] == "succeeded"


@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
@pytest.mark.parametrize("into_reverse", [1.0, 3.0, 5.0])
async def test_a_bump_while_reversing_onto_the_dock_is_handled_and_it_docks(
    base: Base, on_bump: Literal["cancel", "suspend"], into_reverse: float
) -> None:
    """Early, the reflex backs off toward the dock; late, into it (a stall: it just turns)."""
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        await robot.undock()
        reflex = robot.whenever("bumper", becomes=True).do(
            bumper_reflex if on_bump == "cancel" else suspending_reflex
        )
        dock = robot.dock()
        while not log.of_kind(EventKind.ACTION_FINISHED, "navigate_to"):
            await robot.sleep(robot.control_period)
        # Reversing at 5 cm/s, 0.28 m from the dock: the bump comes once it has reversed that
        # many seconds' worth (counted in metres, which a ROS 2 base's sim-node falling behind
        # the robot's clock does not shift).
        start = robot.odom_pose()[:2]
        await robot.wait(
            lambda r: math.dist(r.odom_pose()[:2], start) >= REVERSE_SPEED * into_reverse,
            poll=robot.control_period,
        )
        robot.state.update(bumper=True, bumper_left=True, bumper_right=False)
        if await dock.wait_done() is Outcome.CANCELLED:  # then the walk docks again
            for handle in robot.handles():
                await handle.wait_done()
            await robot.dock()
        assert robot.state.docked
        await reflex.close()
    assert log.outcomes(REFLEXES[on_bump]) == ["succeeded"]
    backing_off = log.outcomes("drive_distance")[1]  # the undock's, then the reflex's
    assert backing_off == ("failed" if into_reverse > 1 else "succeeded")  # a stall: turned
    if on_bump == "suspend":  # the suspended dock lined up again, then docked
        assert dock.outcome is Outcome.SUCCEEDED
        assert log.names_started().count("navigate_to") == 2


async def test_without_a_bump_the_walk_has_none_of_its_own(base: Base) -> None:
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        report = await random_walk(robot, moves=3, seed=0)
    assert (report.moves, report.bumps, report.docked) == (3, 0, True)
    started = log.names_started()
    counts = {name: started.count(name) for name in ("undock", "drive_distance", "rotate_angle")}
    assert counts == {"undock": 1, "drive_distance": 5, "rotate_angle": 3}
    assert (started.count("dock"), started.count("navigate_to")) == (1, 1)


async def test_a_bump_on_the_dock_turns_away_without_backing_into_the_dock(base: Base) -> None:
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        robot.state.update(bumper=True, bumper_left=True, bumper_right=False)
        ticks = robot.state.version("v")
        await bumper_reflex(robot)
        # Backing into the dock would stall the wheels. Counted in the base's own ticks: a
        # sim-node that a loaded machine holds back simulates fewer seconds than its loop counts.
        assert (robot.state.version("v") - ticks) * robot.control_period < 2.0
        assert robot.odom_pose()[2] == pytest.approx(-0.9, abs=0.01)
    assert log.names_started() == ["bumper_reflex", "rotate_angle"]
