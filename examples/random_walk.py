"""Random walk with a bumper reflex (lockstep virtual time), on the simulator or in memory.

The behaviour itself lives in `pyrobots_aio.sim.random_walk` so that the
``pyrobots-aio demo random-walk`` command can run it too; read it there. It is
written against `pyrobots_aio.DriveBase`, so the same code runs on the MuJoCo
robot (default) and on `pyrobots_aio.testing.FakeBase` (``--fake``: in memory,
no simulator). This script runs it, as fast as the CPU allows, and prints what
happened.

Run: ``python examples/random_walk.py [--seed N] [--duration SECONDS] [--fake]``
"""

from __future__ import annotations

import argparse

from pyrobots_aio.cli import install_console_handler
from pyrobots_aio.sim import SimRobot, run
from pyrobots_aio.sim.random_walk import WalkReport, random_walk
from pyrobots_aio.testing import FakeBase


async def main(seed: int = 0, duration: float | None = None, fake: bool = False) -> WalkReport:
    async with FakeBase() if fake else SimRobot(seed=seed) as robot:
        return await random_walk(robot, duration=duration, seed=seed)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds")
    parser.add_argument("--fake", action="store_true", help="run on FakeBase, not the simulator")
    options = parser.parse_args()
    install_console_handler()
    report = run(main, options.seed, options.duration, options.fake)
    print(
        f"{report.moves} moves, {report.bumps} bumps handled, {report.interrupted} moves "
        f"interrupted, {'docked' if report.docked else 'NOT docked'}, "
        f"{report.sim_time:.1f} s simulated"
    )
