"""SimRobot's trajectories, pinned to the last bit across the DriveBase refactor.

The figures were recorded on the code before the motion actions moved onto
`DriveBase` (commit 8e7e2b3): the true pose (``world.base_pose()``), the
odometry and the tick count at the end of lockstep runs, as ``float.hex``.
Moving code must not change a single bit of them; a deliberate change of
the physics, the controllers or the walk re-records them (and says why).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


def _end(robot: SimRobot) -> dict[str, Any]:
    return {
        "base": [value.hex() for value in robot.world.base_pose()],
        "odom": [value.hex() for value in robot.world.odom_pose()],
        "ticks": robot.sim.ticks,
        "steps": robot.world.steps,
    }


WALKS = {
    0: {
        "base": ["-0x1.b7bd6f7690bfdp+0", "0x1.0576efe01c464p-7", "0x1.027696152337ap-9"],
        "odom": ["-0x1.612c95476ff37p-7", "0x1.72dcddb3efb55p-7", "-0x1.c7f2ca0e0a061p-8"],
        "ticks": 4266,
        "steps": 42660,
        "report": (10, 7, 7, True, "0x1.5547ae147ae15p+6"),
    },
    3: {
        "base": ["-0x1.b7c06a43270d3p+0", "0x1.eec88e7a326ddp-8", "0x1.80b3bd0942419p-9"],
        "odom": ["0x1.70c88313955abp-7", "0x1.89a41a28a936bp-8", "0x1.86f4d52a328fdp-8"],
        "ticks": 4042,
        "steps": 40420,
        "report": (10, 1, 1, True, "0x1.435c28f5c28f6p+6"),
    },
}


@pytest.mark.parametrize("seed", sorted(WALKS))
async def test_random_walk_ends_where_it_always_did(seed: int) -> None:
    async with SimRobot(seed=seed) as robot:
        report = await random_walk(robot, seed=seed)
        end = _end(robot)
    end["report"] = (
        report.moves,
        report.bumps,
        report.interrupted,
        report.docked,
        report.sim_time.hex(),
    )
    assert end == WALKS[seed]


SEQUENCE = {
    "base": ["-0x1.b7d4c6abb3631p+0", "0x1.3a399050f9b54p-9", "0x1.659b825940f7bp-9"],
    "odom": ["0x1.669d16448aac1p-7", "-0x1.8b4b5ed19c65ep-11", "0x1.7a49db3b7af4bp-8"],
    "ticks": 1992,
    "steps": 19920,
    "results": [
        "0x1.99b7340c79fc4p-1",
        "-0x1.9225c094ec094p+0",
        "-0x1.3314e1cb6fadep-2",
        "0x1.00489d7859fcfp+0",
    ],
    "docked": True,
}


async def test_every_motion_action_ends_where_it_always_did() -> None:
    async with SimRobot(seed=1) as robot:
        await robot.undock()
        results = [
            await robot.drive_distance(0.8),
            await robot.rotate_angle(-math.pi / 2),
            await robot.drive_distance(-0.3, speed=0.1),
        ]
        await robot.navigate_to((0.0, 0.5, 0.0, 0.0, 0.0, math.pi / 2))
        results.append(await robot.rotate_angle(1.0, speed=0.5))
        await robot.dock()
        await robot.sleep(0.5)
        end = _end(robot)
        end["results"] = [value.hex() for value in results]
        end["docked"] = robot.state.docked
    assert end == SEQUENCE
