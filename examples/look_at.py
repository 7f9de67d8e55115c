"""Look at: turn a pan-tilt head toward a point given in any frame (the paper's example).

The robot stands at (1, 2) in the map, facing +y; its head is 1 m above its
base. The target is one metre to the left of the robot, ``(0, 1, 0,
"base_link")``: the head must pan +90° (left) and tilt 45° down. The same point
written in the map frame gives the same answer.

Run: ``python examples/look_at.py``
"""

from __future__ import annotations

import asyncio
import logging
import math

from pyrobots_aio import FrameTree, PoseLike, Robot, action
from pyrobots_aio.cli import install_console_handler

PAN_SPEED = math.radians(90)  # rad/s, the head's top speed


@action
async def look_at(robot: Robot, target: PoseLike) -> tuple[float, float]:
    """Turn the head toward ``target`` at the head's speed; return the final (pan, tilt)."""
    pan, tilt = robot.poses.pantilt(target, ref="head_base")
    start_pan, start_tilt = robot.state.pan, robot.state.tilt
    duration = max(abs(pan - start_pan), abs(tilt - start_tilt)) / PAN_SPEED
    steps = max(1, math.ceil(duration / 0.05))
    for i in range(1, steps + 1):
        await robot.sleep(duration / steps)
        robot.state.update(
            pan=start_pan + (pan - start_pan) * i / steps,
            tilt=start_tilt + (tilt - start_tilt) * i / steps,
        )
    return pan, tilt


async def main() -> tuple[float, float, float, float]:
    async with Robot() as robot:
        frames = FrameTree()
        frames.set_transform("map", "base_link", (1.0, 2.0, 0.0, 0.0, 0.0, math.pi / 2))
        frames.set_transform("base_link", "head_base", (0.0, 0.0, 1.0))
        robot.poses.add_frame_provider(frames)
        robot.state.update(pan=0.0, tilt=0.0)

        target = (0.0, 1.0, 0.0, "base_link")
        pan, tilt = await look_at(robot, target)
        print(
            f"target {target}: pan {math.degrees(pan):+.1f} deg, tilt {math.degrees(tilt):+.1f} deg"
        )

        same_point = robot.poses.inframe(target, "map")
        print(f"the same point in the map: ({same_point.x:.2f}, {same_point.y:.2f})")
        pan2, _ = await look_at(robot, same_point)
        print(f"looking at it again from the map pose: pan {math.degrees(pan2):+.1f} deg")
        return pan, tilt, same_point.x, same_point.y


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    asyncio.run(main())
