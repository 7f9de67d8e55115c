"""Resources: lift a box with both arms, wave, scratch your head (the pyRobots listing).

``lift_box`` holds the compound ARMS (both arms, taken atomically);
``wave_hand`` needs the left arm, so it waits; ``scratch_head`` asks with
``wait=False`` and is skipped while the arm is busy. Then a ``preempt=True``
action with a higher priority takes the arms from a long ``lift_box``.

Run: ``python examples/resources.py``
"""

from __future__ import annotations

import asyncio
import logging

from pyrobots_aio import (
    ActionInterrupted,
    ActionSkipped,
    CompoundResource,
    Outcome,
    Resource,
    Robot,
    action,
    lock,
)
from pyrobots_aio.cli import install_console_handler

L_ARM, R_ARM = Resource("l_arm"), Resource("r_arm")
ARMS = CompoundResource(L_ARM, R_ARM, name="arms")


@action
@lock(ARMS)
async def lift_box(robot: Robot, seconds: float = 0.3) -> str:
    await robot.sleep(seconds)
    return "box lifted"


@action
@lock(L_ARM)
async def wave_hand(robot: Robot) -> str:
    await robot.sleep(0.1)
    return "waved"


@action
@lock(L_ARM, wait=False)
async def scratch_head(robot: Robot) -> str:
    await robot.sleep(0.1)
    return "scratched"


@action
@lock(ARMS, priority=10, preempt=True)
async def catch_falling_cup(robot: Robot) -> str:
    await robot.sleep(0.1)
    return "cup caught"


async def main() -> dict[str, Outcome]:
    async with Robot() as robot:
        lift, wave, scratch = lift_box(robot), wave_hand(robot), scratch_head(robot)
        await asyncio.sleep(0.01)
        print(robot.action_tree())
        print(await lift, "then", await wave)
        try:
            await scratch
        except ActionSkipped as skipped:
            print(f"scratch_head: {skipped}")

        long_lift = lift_box(robot, 60.0)
        await asyncio.sleep(0.01)
        catch = catch_falling_cup(robot)
        try:
            await long_lift
        except ActionInterrupted as preempted:
            print(f"lift_box: {preempted.reason}")
        print(await catch)
        handles = {"lift_box": lift, "wave_hand": wave, "scratch_head": scratch}
        handles |= {"long_lift_box": long_lift, "catch_falling_cup": catch}
        return {name: handle.outcome for name, handle in handles.items()}


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    for name, outcome in asyncio.run(main()).items():
        print(f"{name:18} {outcome.name}")
