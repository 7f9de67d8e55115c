"""Static checks of the motion layer's typing, run by ``mypy --strict tests/typing``.

The motion actions are `DriveBase` methods: every base (SimRobot, FakeBase)
gives the same typed handles, and the random walk takes any base.
"""

from __future__ import annotations

from typing import assert_type

from pyrobots_aio import ActionHandle, DriveBase
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import WalkReport, random_walk
from pyrobots_aio.testing import FakeBase, Injection, inject_bump


async def every_base_gives_the_same_typed_motion(base: DriveBase) -> None:
    assert_type(base.drive_distance(0.5), ActionHandle[float])
    assert_type(base.rotate_angle(1.0, speed=0.5), ActionHandle[float])
    assert_type(base.navigate_to((1.0, 0.0, 0.0)), ActionHandle[None])
    assert_type(base.dock(), ActionHandle[None])
    assert_type(base.odom_pose(), tuple[float, float, float])
    base.drive(0.1, 0.0)
    base.drive_distance("far")  # type: ignore[arg-type]


async def the_walk_runs_on_any_base(sim: SimRobot, fake: FakeBase) -> None:
    assert_type(await random_walk(sim, seed=1), WalkReport)
    assert_type(await random_walk(fake, moves=3), WalkReport)
    assert_type(inject_bump(fake, "undock", side="left"), Injection)
    inject_bump(fake, "undock", side="top")  # type: ignore[arg-type]
    assert_type(await random_walk(fake, on_bump="suspend"), WalkReport)
    await random_walk(fake, on_bump="stop")  # type: ignore[arg-type]
