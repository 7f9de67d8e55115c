"""FakeBase's trajectories, pinned bit for bit (issue 27: exploring faster, the same runs).

The figures were recorded on the code before FakeBase's tick was made
cheaper for the explorer: a digest of the whole state (value, timestamp and
version of every key) after every tick, the true pose and the odometry at
the end (``float.hex``), the tick count; for explored runs also the hits and
their times. The worlds cover what the sensors compute: walls, boxes, a dock
turned a quarter (a box that is not axis-aligned), the bumper held, a sensor
silenced and the odometry frozen by the explorer's tamper. If a change of the
fake's physics is intended, print the new figures and replace them, saying why.
"""

from __future__ import annotations

import asyncio
import hashlib
import math
from dataclasses import astuple
from typing import Any

import pytest

from pyrobots_aio.sim.random_walk import random_walk
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    Cancel,
    EmergencyStop,
    Hit,
    On,
    Pause,
    Preempt,
    Reading,
    Scenario,
    Silence,
    StaleOdometry,
)


class _TickDigest:
    """Hashes the whole state (value, timestamp, version of every key) after every tick."""

    def __init__(self, robot: FakeBase) -> None:
        self.robot = robot
        self.hash = hashlib.sha256()

    def __call__(self) -> bool:
        state = self.robot.state
        row = [(key, *astuple(state.sample(key))) for key in sorted(state)]
        self.hash.update(repr((self.robot.time(), row)).encode())
        return False  # never done: called after every tick until cancelled


def _crowded() -> FakeBase:
    """A room with two boxes and the dock on the south wall, turned a quarter."""
    return FakeBase(
        dock=(0.0, -1.9, math.pi / 2),
        obstacles=[(0.3, -0.2, 0.7, 0.4), (-1.2, 0.8, -0.6, 1.1)],
    )


class _Walk:
    """A random walk that digests every tick of the robot it runs on."""

    def __init__(self, moves: int, seed: int) -> None:
        self.moves, self.seed = moves, seed
        self.digest = ""

    async def __call__(self, robot: FakeBase) -> tuple[Any, ...]:
        digest = _TickDigest(robot)
        watcher = asyncio.create_task(robot.fake.control(digest))
        try:
            report = await random_walk(robot, moves=self.moves, seed=self.seed)
        finally:
            watcher.cancel()
            self.digest = digest.hash.hexdigest()
        return astuple(report)


def _end(robot: FakeBase) -> dict[str, Any]:
    return {
        "base": [value.hex() for value in robot.world.base_pose()],
        "odom": [value.hex() for value in robot.world.odom_pose()],
        "ticks": robot.ticks,
    }


# recorded on commit 0917e9b
WALKS: dict[str, dict[str, Any]] = {
    "crowded-1": {
        "base": ["-0x1.c14377caaa154p-13", "-0x1.b78fb0df5aae9p+0", "0x1.9227038557e01p+0"],
        "digest": "ac68b73a3eded3a90ecfba6781f4fcf9864bd26ecfc96b6dad23996b00d8e900",
        "odom": ["0x1.467d946b43e40p-7", "0x1.c14377c961a9ap-13", "0x1.d390454508fc0p-14"],
        "report": (8, 4, 0, True, 101.14),
        "ticks": 5057,
    },
    "room-0": {
        "base": ["-0x1.b7901aeef5a41p+0", "0x1.3703a44ad51d5p-7", "-0x1.c34e5052c9b10p-12"],
        "digest": "0b65adc4a13c5363ed162787a9ed2c8e63b62fe07c2312cd2124fd037d14945e",
        "odom": ["0x1.46488c9dbef54p-7", "0x1.3703a44ad51d5p-7", "-0x1.c34e5052c9b10p-12"],
        "report": (8, 5, 5, True, 71.9),
        "ticks": 3595,
    },
    "room-3": {
        "base": ["-0x1.b7bf4f38c89fap+0", "-0x1.1419817c2d61ap-7", "-0x1.1fd61422d55c0p-14"],
        "digest": "8bd105186b92d81a82352d261a5227a2e53c83b467dd0b65ed6bd2b542200d6b",
        "odom": ["0x1.2eae67b44d04ep-7", "-0x1.1419817c2d61ap-7", "-0x1.1fd61422d55c0p-14"],
        "report": (8, 0, 0, True, 69.68),
        "ticks": 3484,
    },
}


@pytest.mark.parametrize(("world", "seed"), [("room", 0), ("room", 3), ("crowded", 1)])
def test_a_random_walk_on_fakebase_ends_where_it_always_did(world: str, seed: int) -> None:
    walk = _Walk(moves=8, seed=seed)
    base = FakeBase if world == "room" else _crowded
    run = Scenario(walk, base=base).run()
    end = {**_end(run.robot), "report": run.result, "digest": walk.digest}
    assert end == WALKS[f"{world}-{seed}"]


SCHEDULES: dict[str, list[Hit]] = {
    "held bumps": [
        Hit(Bump("left", hold=0.5), On("drive_distance", 2)),
        Hit(Bump("both", hold=2.0), At(21.5)),
    ],
    "silence and stale odometry": [
        Hit(Silence("bumper", 2.0), On("rotate_angle", 1, "end")),
        Hit(StaleOdometry(0.5), At(12.0)),
        Hit(Reading("front_center", 0.02, hold=0.5), At(30.0)),
    ],
    "pause, preempt, e-stop": [
        Hit(Pause(1.0), At(5.0)),
        Hit(Preempt(1.0), At(20.0)),
        Hit(EmergencyStop(0.5), At(35.0)),
    ],
    "cancel": [Hit(Cancel("rotate_angle"), On("rotate_angle", 2))],
}

# recorded on commit 0917e9b
EXPLORED: dict[str, dict[str, Any]] = {
    "cancel": {
        "base": ["-0x1.44c9e7b3cb430p-8", "-0x1.b78d5894fbf90p+0", "0x1.923e1b8f4720fp+0"],
        "digest": "3b4a277f1976eeb6735c67998228efd7304bc1413476574f7c2c25afc1c4b117",
        "error": "None",
        "hits": [("0x1.b28f5c28f5c29p+3", Hit(Cancel("rotate_angle"), On("rotate_angle", nth=2)))],
        "odom": ["0x1.47a9b99a99964p-7", "0x1.44c9e7b3c8887p-8", "0x1.e664b045419f0p-12"],
        "result": (6, 2, 3, True, 55.6),
        "ticks": 2780,
        "time": "0x1.bcccccccccccdp+5",
    },
    "held bumps": {
        "base": ["-0x1.2f382ee8f40b5p-7", "-0x1.b79b96604cccap+0", "0x1.9221a07935876p+0"],
        "digest": "3eed50a65b94101d54ea1c6ef4b426f42529d0c10f82a1e9a0328befa58d50fd",
        "error": "None",
        "hits": [
            ("0x1.2e147ae147ae1p+1", Hit(Bump("left", hold=0.5), On("drive_distance", nth=2))),
            ("0x1.5800000000000p+4", Hit(Bump(hold=2.0), At(21.5))),
        ],
        "odom": ["0x1.408ad3f22cad4p-7", "0x1.2f382ee8f22ddp-7", "0x1.eb34f2b65d700p-16"],
        "result": (6, 7, 5, True, 61.120000000000005),
        "ticks": 3056,
        "time": "0x1.e8f5c28f5c290p+5",
    },
    "pause, preempt, e-stop": {
        "base": ["-0x1.144288b4b3506p+0", "-0x1.b2e1da6f011cap+0", "-0x1.3659e5af8b305p+1"],
        "digest": "57d05714038ed57d2b7237310bf79cfc520de0e105210c7f0d6e7a6d66727244",
        "error": 'EmergencyStopError("rotate_angle refused: the emergency stop '
        "is latched ('explore: EmergencyStop'); call "
        'robot.clear_emergency_stop() once it is safe to move")',
        "hits": [
            ("0x1.4000000000000p+2", Hit(Pause(), At(5.0))),
            ("0x1.4000000000000p+4", Hit(Preempt(1.0), At(20.0))),
            ("0x1.1800000000000p+5", Hit(EmergencyStop(0.5), At(35.0))),
        ],
        "odom": ["0x1.ceb4664c048a9p-6", "0x1.144288b4b3500p+0", "0x1.24d5aa36d90adp+1"],
        "result": None,
        "ticks": 1750,
        "time": "0x1.1800000000000p+5",
    },
    "silence and stale odometry": {
        "base": ["-0x1.3d95d7332c4dbp-7", "-0x1.b7cd6e5551af6p+0", "0x1.91d296888a9e6p+0"],
        "digest": "57ebd06dd5643c9b1cf16455823a6775c96659e2f8f6332b08588cb26e5be3b6",
        "error": "None",
        "hits": [
            ("0x1.1eb851eb851ecp+3", Hit(Silence(seconds=2.0), On("rotate_angle", at="end"))),
            ("0x1.8000000000000p+3", Hit(StaleOdometry(0.5), At(12.0))),
            ("0x1.e000000000000p+4", Hit(Reading(hold=0.5), At(30.0))),
        ],
        "odom": ["0x1.279ed96fbc9a8p-7", "0x1.3d95d7332a1a2p-7", "-0x1.347aeee0bd0e4p-10"],
        "result": (6, 2, 2, True, 59.54),
        "ticks": 2977,
        "time": "0x1.dc51eb851eb85p+5",
    },
}


@pytest.mark.parametrize("name", sorted(SCHEDULES))
def test_an_explored_run_on_fakebase_ends_where_it_always_did(name: str) -> None:
    walk = _Walk(moves=6, seed=2)
    scenario = Scenario(walk, base=_crowded, invariants=())
    run = scenario.run(SCHEDULES[name])
    end = {
        **_end(run.robot),
        "result": run.result,
        "error": repr(run.error),
        "hits": [(time.hex(), hit) for time, hit in run.hits],
        "time": run.time.hex(),
        "digest": walk.digest,
    }
    assert end == EXPLORED[name]
