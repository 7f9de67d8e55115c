"""Benchmarks of the simulated robot: tick cost and lockstep real-time factors (DESIGN.md §10)."""

from __future__ import annotations

import time

import mujoco

from pyrobots_aio.sim import SimRobot, SimWorld
from pyrobots_aio.sim import run as run_lockstep
from pyrobots_aio.sim.random_walk import random_walk

IDLE_SECONDS = 120.0
WALK_SECONDS = 300.0


def _tick_cost() -> dict[str, float]:
    """One control tick of SimWorld, and, as a yardstick, ten bare mj_step of the same model."""
    world = SimWorld()
    world.set_command(0.2, 0.3)
    ticks = 2_000
    start = time.perf_counter()
    for _ in range(ticks):
        world.step(10)
        world.read_sensors()
    physics = (time.perf_counter() - start) / ticks
    model, data = world._model, world._data
    start = time.perf_counter()
    for _ in range(ticks):
        mujoco.mj_step(model, data, nstep=10)
    bare = (time.perf_counter() - start) / ticks
    return {"physics_tick_us": physics * 1e6, "bare_mj_step_x10_us": bare * 1e6}


async def _idle() -> float:
    async with SimRobot() as robot:
        start = time.perf_counter()
        await robot.sleep(IDLE_SECONDS)
        return time.perf_counter() - start


async def _walk() -> tuple[float, float]:
    async with SimRobot(seed=1) as robot:
        start = time.perf_counter()
        report = await random_walk(robot, duration=WALK_SECONDS, seed=1)
        return report.sim_time, time.perf_counter() - start


def run() -> dict[str, float]:
    """Measure the simulator; return the figures."""
    figures = _tick_cost()
    idle_wall = run_lockstep(_idle)
    figures["control_tick_us_with_executive"] = idle_wall / (IDLE_SECONDS * 50) * 1e6
    figures["idle_realtime_factor"] = IDLE_SECONDS / idle_wall
    sim_time, wall = run_lockstep(_walk)
    figures["random_walk_sim_seconds"] = sim_time
    figures["random_walk_realtime_factor"] = sim_time / wall
    return figures
