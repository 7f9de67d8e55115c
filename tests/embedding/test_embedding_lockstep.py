"""Lockstep simulation from inside a running app: ``await asyncio.to_thread(sim.run, main)``."""

from __future__ import annotations

import asyncio

import pytest

import pyrobots_aio.sim
from pyrobots_aio import EventLoopError, Outcome, Robot, action
from pyrobots_aio.loops import is_virtual
from pyrobots_aio.sim import SimRobot


async def dry_run(distance: float) -> tuple[Outcome, float, bool]:
    """Undock and drive ``distance`` metres, in lockstep virtual time."""
    async with SimRobot(seed=1) as sim:
        await sim.undock()
        outcome = await sim.drive_distance(distance).wait_done()
        return outcome, sim.time(), is_virtual()


@action
async def patrol(robot: Robot, laps: int) -> int:
    for _ in range(laps):
        await robot.sleep(0.01)
    return laps


@pytest.mark.asyncio
async def test_sim_run_inside_the_app_s_loop_says_to_use_a_thread() -> None:
    with pytest.raises(EventLoopError) as refused:
        pyrobots_aio.sim.run(dry_run, 0.5)
    assert str(refused.value) == (
        "pyrobots_aio.sim.run(dry_run) cannot run inside a running event loop: it runs "
        "dry_run on a virtual-time loop of its own; from async code, run it in a thread: "
        "await asyncio.to_thread(pyrobots_aio.sim.run, dry_run)"
    )


@pytest.fixture(scope="module")
def reference() -> tuple[Outcome, float, bool]:
    """The same run from plain synchronous code, where no loop runs."""
    return pyrobots_aio.sim.run(dry_run, 0.5)


@pytest.mark.asyncio
async def test_lockstep_runs_in_threads_beside_the_app_s_own_robot(
    reference: tuple[Outcome, float, bool],
) -> None:
    assert not is_virtual()  # the app runs in real time
    async with Robot() as robot:
        app_work = patrol(robot, 5)
        one, two = await asyncio.gather(
            asyncio.to_thread(pyrobots_aio.sim.run, dry_run, 0.5),
            asyncio.to_thread(pyrobots_aio.sim.run, dry_run, 0.5),
        )
        assert await app_work == 5
    outcome, sim_seconds, virtual = one
    assert (outcome, virtual) == (Outcome.SUCCEEDED, True)
    assert sim_seconds > 5  # undocking and half a metre: seconds of simulated time
    # two lockstep runs at once, each on a loop of its own: the very run of plain code
    assert one == two == reference
