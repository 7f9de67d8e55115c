"""`Ros2Robot` driving sim-node processes: a sim-node killed mid-walk, and two robots at once.

The sim-nodes run four times faster than real time, and so does the test's
loop (``LOOP_RATE``): the test's seconds are simulated seconds.
"""

from __future__ import annotations

import asyncio
import signal
from typing import TYPE_CHECKING

import pytest
from ros2_support import (
    DEADLINE,
    PEER_SILENCE,
    assert_stale_error,
    require_rclpy,
    require_sim,
    silence_options,
    sim_node_process,
)

require_rclpy()
require_sim()

from geometry_msgs.msg import Twist  # noqa: E402

from pyrobots_aio import MotionError  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402
from pyrobots_aio.sim.random_walk import random_walk  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

LOOP_RATE = 4.0
TIMEOUT = DEADLINE * LOOP_RATE  # the loop's seconds: DEADLINE seconds of the wall clock
ODOM_TIMEOUT = PEER_SILENCE * LOOP_RATE
"""The loop's seconds without odometry before it is stale: `PEER_SILENCE` of the wall clock."""

pytestmark = pytest.mark.asyncio


async def test_a_sim_node_killed_mid_walk_makes_the_walk_fail_stale_not_hang(
    plain: Callable[..., PlainNode],
) -> None:
    cmd_vel = plain("listener").inbox("/doomed/cmd_vel", Twist)
    # The robot waits PEER_SILENCE for odometry, not the default 0.5 s (an eighth of a wall-clock
    # second at 4x, which a loaded machine holds either process up for): the walk fails stale
    # that much later, and the rest is the same.
    doomed = Ros2Robot(namespace="/doomed", odom_timeout=ODOM_TIMEOUT)
    with sim_node_process("--namespace", "/doomed", *silence_options(LOOP_RATE)) as process:
        async with asyncio.timeout(TIMEOUT), doomed as robot:
            await robot.cmd_vel.wait_for_subscribers(2)  # the sim-node's and the listener's
            walk = asyncio.ensure_future(random_walk(robot, duration=60))
            await robot.wait(
                lambda r: r.odom_pose()[0] > 0.6, poll=0.05
            )  # undocked and driving out
            assert not walk.done()
            process.send_signal(signal.SIGKILL)
            with pytest.raises(MotionError) as caught:
                await walk
            assert_stale_error(caught.value, "/doomed", ODOM_TIMEOUT)
            assert robot.state.odom_stale is True
            age = robot.odom_age()
            assert age is not None
            assert age >= ODOM_TIMEOUT
            assert robot.handles() == []  # the walk, its moves and its reflex: all over
            with pytest.raises(MotionError, match=r"^odometry on /doomed/odom is stale"):
                robot.drive(0.2, 0.0)
            with pytest.raises(MotionError, match=r"^odometry on /doomed/odom is stale"):
                await robot.drive_distance(0.3)
            await robot.sleep(0.5)  # what was sent is in
            last = None
            while not cmd_vel.empty():
                last = cmd_vel.get_nowait()
            assert last is not None
            assert (last.linear.x, last.angular.z) == (0.0, 0.0)  # the base was told to stop
            await robot.sleep(1.0)
            assert cmd_vel.empty()  # and then left alone


async def test_two_robots_in_two_sim_nodes_are_driven_from_one_executive() -> None:
    with (
        sim_node_process("--namespace", "/robot1", *silence_options(LOOP_RATE)),
        sim_node_process("--namespace", "/robot2", "--seed", "2", *silence_options(LOOP_RATE)),
    ):
        async with (
            asyncio.timeout(TIMEOUT),
            Ros2Robot(namespace="/robot1", odom_timeout=ODOM_TIMEOUT) as one,
            Ros2Robot(namespace="/robot2", odom_timeout=ODOM_TIMEOUT) as two,
        ):
            first, second = await asyncio.gather(
                random_walk(one, moves=2, seed=1), random_walk(two, moves=2, seed=2)
            )
            assert (first.moves, first.docked, second.moves, second.docked) == (2, True, 2, True)
            assert one.state.docked
            assert two.state.docked
            # Each went its own way: one robot's walk is not the other's.
            await one.undock()
            assert one.odom_pose()[0] > 0.3
            assert not one.state.docked
            assert two.state.docked
            assert two.odom_pose() != pytest.approx(one.odom_pose(), abs=0.1)
