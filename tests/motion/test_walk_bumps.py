"""A bump at any moment of the random walk: the reflex acts, the walk goes on, and docks.

The Create 3 script's bug class (DESIGN §1): its reflex cancelled the current
goal and control never came back. Here a bump is injected at every action
boundary of a three-move walk (seed 0: no bump of its own on any base), in
virtual time, on every base.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import pytest

from pyrobots_aio import EventKind
from pyrobots_aio.sim.random_walk import bumper_reflex, random_walk
from pyrobots_aio.testing import EventLog, inject_bump

if TYPE_CHECKING:
    from .conftest import Base

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

Boundary = tuple[str, int, Literal["start", "end"]]
# Seed 0, three moves: undock (its own drive_distance #1), drive out (#2), then three
# moves (rotate_angle #k, drive_distance #k+2), then dock (its navigate_to, then reversing).
BOUNDARIES: list[Boundary] = [
    *((name, nth, at) for name, count in [("undock", 1), ("drive_distance", 5),
        ("rotate_angle", 3), ("navigate_to", 1)] for nth in range(1, count + 1)
        for at in ("start", "end")),
    ("dock", 1, "start"),
]  # fmt: skip


@pytest.mark.parametrize(("name", "nth", "at"), BOUNDARIES)
async def test_a_bump_at_any_boundary_is_handled_and_the_walk_docks(
    base: Base, name: str, nth: int, at: Literal["start", "end"]
) -> None:
    log = EventLog()
    async with base.make(instruments=[log]) as robot:
        with inject_bump(robot, name, nth=nth, at=at) as bump:
            report = await random_walk(robot, moves=3, seed=0)
        assert bump.done
        assert robot.state.docked
        assert not robot.state.bumper
        assert robot.handles() == []
    assert report.moves == 3  # control came back to the walk
    assert report.docked
    assert report.bumps >= 1  # the injected one, and any its detour ran into
    reflex = log.first(EventKind.ACTION_STARTED, "bumper_reflex")
    assert bump.time is not None
    assert reflex.time == pytest.approx(bump.time)  # the reflex ran at once ...
    assert set(log.outcomes("bumper_reflex")) == {"succeeded"}  # ... and to its end


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
        start = robot.time()
        await bumper_reflex(robot)
        assert robot.time() - start < 2.0  # backing into the dock would stall the wheels
        assert robot.odom_pose()[2] == pytest.approx(-0.9, abs=0.01)
    assert log.names_started() == ["bumper_reflex", "rotate_angle"]
