"""`Ros2Robot(profile="create3")` against ``sim-node --profile create3``: the walk, unchanged.

Both run four times faster than real time (``LOOP_RATE``): the test's seconds
are simulated seconds.
"""

from __future__ import annotations

import asyncio
from typing import Literal

import pytest
from ros2_support import (
    DEADLINE,
    PEER_SILENCE,
    require_interfaces,
    require_rclpy,
    require_sim,
    silence_options,
    sim_node_process,
)

require_rclpy()
require_sim()
require_interfaces("irobot_create_msgs")

from rclpy.action import get_action_client_names_and_types_by_node  # noqa: E402

from pyrobots_aio import EventKind  # noqa: E402
from pyrobots_aio.motion import SENSORS  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402
from pyrobots_aio.sim.random_walk import random_walk, suspending_reflex  # noqa: E402
from pyrobots_aio.testing import EventLog  # noqa: E402

LOOP_RATE = 4.0
TIMEOUT = DEADLINE * LOOP_RATE  # the loop's seconds: DEADLINE seconds of the wall clock
NODE = ("--namespace", "/create3", "--profile", "create3", *silence_options(LOOP_RATE))
ODOM_TIMEOUT = PEER_SILENCE * LOOP_RATE
"""The loop's seconds without odometry before it is stale: `PEER_SILENCE` of the wall clock.

The walks are not about staleness, and a loaded machine holds either process up for longer
than the default 0.5 s (an eighth of a wall-clock second at 4x); the sim-node holds each
command as long (`silence_options`).
"""

pytestmark = pytest.mark.asyncio


@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
async def test_a_create3_robot_reads_its_hazards_ir_and_dock_and_walks_unchanged(
    on_bump: Literal["cancel", "suspend"],
) -> None:
    with sim_node_process(*NODE):
        async with (
            asyncio.timeout(TIMEOUT),
            Ros2Robot(namespace="/create3", profile="create3", odom_timeout=ODOM_TIMEOUT) as robot,
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
            report = await random_walk(robot, moves=3, seed=1, on_bump=on_bump)
            assert (report.moves, report.docked) == (3, True)
            if on_bump == "suspend":
                assert report.interrupted == 0
            assert robot.state.docked
            # It undocked and docked through the base's own action servers.
            ros2 = robot.ros2
            clients = get_action_client_names_and_types_by_node(ros2.node, ros2.name, "/create3")
            assert dict(clients) == {
                "/create3/dock": ["irobot_create_msgs/action/Dock"],
                "/create3/undock": ["irobot_create_msgs/action/Undock"],
            }


@pytest.mark.parametrize("motion", ["undock", "dock"])
async def test_a_docking_suspended_by_a_bump_stops_the_base_s_goal_and_sends_it_again(
    motion: str,
) -> None:
    """``random_walk(on_bump="suspend")``'s reflex, on a base that docks and undocks itself.

    Left to its goal, the base would fight the reflex for the wheels: the freeze cancels the
    base's goal (the base stops), and the thawed action sends it again.
    """
    log = EventLog()
    with sim_node_process(*NODE):
        async with (
            asyncio.timeout(TIMEOUT),
            Ros2Robot(
                namespace="/create3",
                profile="create3",
                odom_timeout=ODOM_TIMEOUT,
                instruments=[log],
            ) as robot,
        ):
            if motion == "dock":
                await robot.undock()
                await robot.drive_distance(0.5)  # a longer way back to the dock
            reflex = robot.whenever("bumper", becomes=True).do(suspending_reflex)
            docking = getattr(robot, motion)()
            await robot.wait(lambda r: abs(r.state.v) > 0.02)  # the base drives its goal
            robot.state.update(bumper=True, bumper_left=True, bumper_right=False)
            await docking
            assert robot.state.docked is (motion == "dock")
            await reflex.close()
    assert log.outcomes(suspending_reflex.name) == ["succeeded"]
    assert log.outcomes(f"goal /create3/{motion}") == ["cancelled", "succeeded"]
    # The base was told to stop (the cancel request went out) before the reflex moved.
    frozen = log.first(EventKind.CANCEL_REQUESTED, f"goal /create3/{motion}")
    reflex = log.first(EventKind.ACTION_STARTED, suspending_reflex.name)
    moves = [  # (on the dock the reflex only turns)
        e
        for e in log.of_kind(EventKind.ACTION_STARTED)
        if e.name in {"drive_distance", "rotate_angle"} and e.time >= reflex.time
    ]
    assert frozen.time <= moves[0].time
