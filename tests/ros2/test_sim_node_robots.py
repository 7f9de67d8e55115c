"""``sim-node --robots 2``: two robots in one simulated world, each under its namespace, one /clock.

The sim-node runs four times faster than real time, and so does the test's
loop (``LOOP_RATE``): the test's seconds are simulated seconds.
"""

from __future__ import annotations

import asyncio
import math
import signal
from typing import TYPE_CHECKING

import pytest
from ros2_support import DEADLINE, require_rclpy, require_sim, sim_node_process, wait_for

require_rclpy()
require_sim()

from pyrobots_aio.cli import main  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

LOOP_RATE = 2.0  # two robots' topics from one process: half the rate of one robot's tests
RATE = ("--rate", str(LOOP_RATE))
TIMEOUT = DEADLINE * LOOP_RATE  # the loop's seconds: DEADLINE seconds of the wall clock
ODOM_TIMEOUT = 2.0  # simulated seconds: a loaded machine delays the node's ticks
RADIUS = 0.171  # of a robot's shell
LANES_APART = 0.5  # the two robots' docks, along y


@pytest.mark.asyncio
async def test_each_robot_has_its_namespace_and_the_world_one_clock(
    plain: Callable[..., PlainNode],
) -> None:
    graph = plain("graph").node
    with sim_node_process("--robots", "2", *RATE) as process:
        async with asyncio.timeout(TIMEOUT):
            nodes = {("sim_node", "/robot1"), ("sim_node", "/robot2")}
            await wait_for(lambda: nodes <= set(graph.get_node_names_and_namespaces()))
            # Each node subscribes to its cmd_vel last, after its publishers (/clock included).
            await wait_for(lambda: graph.count_subscribers("/robot1/cmd_vel") == 1)
            await wait_for(lambda: graph.count_subscribers("/robot2/cmd_vel") == 1)
            await wait_for(lambda: graph.count_publishers("/clock") >= 1)
            topics = dict(graph.get_topic_names_and_types())
            for robot in ("/robot1", "/robot2"):
                assert topics[f"{robot}/odom"] == ["nav_msgs/msg/Odometry"]
                assert topics[f"{robot}/bumper"] == ["std_msgs/msg/Bool"]
                assert topics[f"{robot}/cmd_vel"] == ["geometry_msgs/msg/Twist"]
            assert "/odom" not in topics
            assert "/cmd_vel" not in topics
            assert graph.count_publishers("/clock") == 1  # the world's one clock
            process.send_signal(signal.SIGINT)
            await wait_for(lambda: process.poll() is not None)
        assert process.stdout is not None
        out = process.stdout.read()
    assert process.returncode == 0
    assert out.decode() == "sim-node /robot1/sim_node, /robot2/sim_node stopped\n"


@pytest.mark.asyncio
async def test_one_program_drives_robot1_into_robot2_and_robot1_s_bumper_fires() -> None:
    with sim_node_process("--robots", "2", *RATE):
        async with (
            asyncio.timeout(TIMEOUT),
            Ros2Robot(namespace="/robot1", odom_timeout=ODOM_TIMEOUT) as one,
            Ros2Robot(namespace="/robot2", odom_timeout=ODOM_TIMEOUT) as two,
        ):
            assert (one.state.docked, two.state.docked) == (True, True)  # each on its own dock
            await asyncio.gather(one.drive_distance(0.5), two.drive_distance(0.5))
            await one.rotate_angle(math.pi / 2)  # facing robot2's lane, robot2 beside it
            start = one.odom_pose()
            one.drive(0.1, 0.0)
            await one.wait("bumper", value=True)
            one.stop()
            travelled = math.dist(one.odom_pose()[:2], start[:2])
            # The only thing in the way: robot2, its shell 0.158 m from robot1's.
            assert travelled == pytest.approx(LANES_APART - 2 * RADIUS, abs=0.03)
            assert two.odom_pose()[0] == pytest.approx(0.5, abs=0.03)
            assert two.state.docked is False


def test_a_bad_number_of_robots_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim-node", "--robots", "0"]) == 2
    assert (
        "argument --robots: expected a whole number of robots from 1 to 7, got '0'"
        in capsys.readouterr().err
    )
    assert main(["sim-node", "--robots", "8"]) == 2
    assert "from 1 to 7, got '8'" in capsys.readouterr().err
