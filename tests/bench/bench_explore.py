"""Benchmarks of exploring (issue 27): examples per second of a 60-simulated-second random walk.

Goals: 200 examples on `FakeBase` in at most 20 s, 100 on `SimRobot` in at
most 60 s, on a 2-core machine. Each example is a fresh base running
``random_walk(duration=60)`` (then docking) under a drawn schedule of bumps,
in lockstep virtual time, with the default invariants; the scenario passes,
so every example runs (no early stop at a failure). The search runs in
`WORKERS` forked processes (``Scenario.explore(workers=...)``); besides the
wall time, the CPU seconds of one example (the workers' user time), which
other processes on a shared machine disturb less.
"""

from __future__ import annotations

import resource
import time
from typing import TYPE_CHECKING

from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import WalkReport, random_walk
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import Bump, Scenario

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio import DriveBase

WALK_SECONDS = 60.0
FAKE_EXAMPLES = 200
SIM_EXAMPLES = 100
WORKERS = 2


async def _walk(robot: DriveBase) -> WalkReport:
    return await random_walk(robot, moves=1, duration=WALK_SECONDS, seed=0)


def _explore(base: Callable[[], DriveBase], examples: int) -> tuple[float, float]:
    """Wall seconds for ``examples`` examples, and CPU seconds per example."""
    scenario = Scenario(
        _walk, base=base, disturbances=[Bump], boundaries=("drive_distance", "rotate_angle")
    )
    wall, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    scenario.explore(examples=examples, profile="ci", workers=WORKERS)
    used = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - cpu
    return time.perf_counter() - wall, used / examples


def run() -> dict[str, float]:
    fake_wall, fake_cpu = _explore(FakeBase, FAKE_EXAMPLES)
    sim_wall, sim_cpu = _explore(lambda: SimRobot(seed=1), SIM_EXAMPLES)
    return {
        "explore_fake_examples_per_s": FAKE_EXAMPLES / fake_wall,
        "explore_fake_200_s": fake_wall,
        "explore_fake_cpu_s_per_example": fake_cpu,
        "explore_sim_examples_per_s": SIM_EXAMPLES / sim_wall,
        "explore_sim_100_s": sim_wall,
        "explore_sim_cpu_s_per_example": sim_cpu,
    }
