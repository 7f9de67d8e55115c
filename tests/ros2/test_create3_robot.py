"""`Ros2Robot(profile="create3")` against ``sim-node --profile create3``: the walk, unchanged.

Both run four times faster than real time (``LOOP_RATE``): the test's seconds
are simulated seconds.
"""

from __future__ import annotations

import asyncio

import pytest
from ros2_support import DEADLINE, require_interfaces, require_rclpy, require_sim, sim_node_process

require_rclpy()
require_sim()
require_interfaces("irobot_create_msgs")

from rclpy.action import get_action_client_names_and_types_by_node  # noqa: E402

from pyrobots_aio.motion import SENSORS  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402
from pyrobots_aio.sim.random_walk import random_walk  # noqa: E402

LOOP_RATE = 4.0
TIMEOUT = DEADLINE * LOOP_RATE  # the loop's seconds: DEADLINE seconds of the wall clock
NODE = ("--namespace", "/create3", "--profile", "create3", "--rate", str(LOOP_RATE))

pytestmark = pytest.mark.asyncio


async def test_a_create3_robot_reads_its_hazards_ir_and_dock_and_walks_unchanged() -> None:
    with sim_node_process(*NODE):
        async with (
            asyncio.timeout(TIMEOUT),
            # 2 simulated seconds of silence, half a second of the wall clock: a loaded
            # machine holds a process up that long, and the walk is not about staleness.
            Ros2Robot(namespace="/create3", profile="create3", odom_timeout=2.0) as robot,
        ):
            assert robot.ros.topics == {
                "cmd_vel": "cmd_vel",
                "odom": "odom",
                "hazard_detection": "hazard_detection",
                "ir_intensity": "ir_intensity",
                "dock_status": "dock_status",
                "tf": "tf",
                "tf_static": "tf_static",
            }
            assert {s.key for s in SENSORS} <= set(robot.state)
            assert robot.state.docked is True
            assert robot.state.bumper is False
            assert 0.0 <= robot.state.ir_front_left <= 0.4
            report = await random_walk(robot, moves=3, seed=1)
            assert (report.moves, report.docked) == (3, True)
            assert robot.state.docked
            # It undocked and docked through the base's own action servers.
            ros2 = robot.ros2
            clients = get_action_client_names_and_types_by_node(ros2.node, ros2.name, "/create3")
            assert dict(clients) == {
                "/create3/dock": ["irobot_create_msgs/action/Dock"],
                "/create3/undock": ["irobot_create_msgs/action/Undock"],
            }
