"""The random walk of DESIGN.md §1 done right: every bump handled, never stuck, docked."""

from __future__ import annotations

import subprocess
import sys

import pytest

from pyrobots_aio import EventKind
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time


# Seed 4 used to end pressed against a box, undocked: docking retried the same straight
# line into it, and the last reflex was cancelled as the walk ended. Seed 12 bumps
# during a running reflex (a dropped firing).
@pytest.mark.asyncio
@pytest.mark.parametrize("seed", [3, 4, 12])
async def test_every_bump_is_handled_and_the_walk_docks(seed: int) -> None:
    log = EventLog()
    async with SimRobot(seed=seed, instruments=[log]) as robot:
        report = await random_walk(robot, seed=seed)
        assert not robot.state.bumper  # not left pressed against anything
        assert robot.state.docked
        assert robot.handles() == []
    assert report.moves == 10
    assert report.docked
    assert report.sim_time < 150  # never stuck: about 80 s of walking and docking
    reflexes = log.outcomes("bumper_reflex")
    assert reflexes
    assert set(reflexes) == {"succeeded"}
    started = [
        e
        for e in log.of_kind(EventKind.MONITOR_FIRED, "bumper becomes=True")
        if e.data["callback"] == "started"
    ]
    assert len(started) == len(reflexes) <= report.bumps


def test_the_walk_imports_without_mujoco() -> None:
    # It is written against DriveBase: a ROS 2 robot or FakeBase runs it with no simulator.
    code = (
        "import sys; sys.modules['mujoco'] = None\n"
        "from pyrobots_aio.sim.random_walk import bumper_reflex, random_walk\n"
        "from pyrobots_aio.testing import FakeBase\n"
        "from pyrobots_aio.sim import run\n"
        "async def main():\n"
        "    async with FakeBase() as robot:\n"
        "        return (await random_walk(robot, moves=1)).docked\n"
        "assert run(main)\n"
        "import pyrobots_aio.sim\n"
        "try:\n"
        "    pyrobots_aio.sim.SimRobot()\n"
        "except pyrobots_aio.SimulationUnavailableError:\n"
        "    print('ok')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert (done.returncode, done.stdout, done.stderr) == (0, "ok\n", "")


def test_the_simulator_is_a_motion_base_and_locks_its_wheels() -> None:
    from pyrobots_aio import motion
    from pyrobots_aio.sim import WHEELS

    assert WHEELS is motion.WHEELS
    assert motion.DISTANCE_TOLERANCE == 0.002
    assert issubclass(SimRobot, motion.DriveBase)
