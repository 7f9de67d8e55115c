"""``pyrobots-aio sim-node`` in real subprocesses, driven and read by a plain rclpy node."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import math
import signal
import sys
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, next_where, require_rclpy, require_sim, wait_for

require_rclpy()
require_sim()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import BatteryState, Range  # noqa: E402
from std_msgs.msg import Bool  # noqa: E402

from pyrobots_aio.cli import main  # noqa: E402
from pyrobots_aio.cli._main import parser  # noqa: E402
from pyrobots_aio.cli._sim_robots import sim_robots  # noqa: E402
from pyrobots_aio.motion import STALL_TIMEOUT  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable

    from ros2_support import PlainNode

COMMAND = [sys.executable, "-m", "pyrobots_aio.cli", "sim-node"]
IR = ["front_center_left", "front_center_right", "front_left", "front_right", "left", "right"]
TOPICS = {
    "battery_state": "sensor_msgs/msg/BatteryState",
    "bumper": "std_msgs/msg/Bool",
    "bumper_left": "std_msgs/msg/Bool",
    "bumper_right": "std_msgs/msg/Bool",
    "cliff_front_left": "std_msgs/msg/Bool",
    "cliff_front_right": "std_msgs/msg/Bool",
    "cliff_side_left": "std_msgs/msg/Bool",
    "cliff_side_right": "std_msgs/msg/Bool",
    "cmd_vel": "geometry_msgs/msg/Twist",
    "docked": "std_msgs/msg/Bool",
    "odom": "nav_msgs/msg/Odometry",
    **{f"ir_{place}": "sensor_msgs/msg/Range" for place in [*IR, "side_left"]},
}


@contextlib.asynccontextmanager
async def sim_node(*args: str) -> AsyncIterator[asyncio.subprocess.Process]:
    """A sim-node process, up and ready; killed if the test leaves it running."""
    process = await asyncio.create_subprocess_exec(
        *COMMAND, *args, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE
    )
    try:
        assert process.stdout is not None
        ready = await process.stdout.readline()
        assert b" ready " in ready, ready + await process.stderr.read()  # type: ignore[union-attr]
        yield process
    finally:
        if process.returncode is None:
            process.kill()
        await process.wait()


async def stop(process: asyncio.subprocess.Process, how: signal.Signals) -> tuple[int, str]:
    """Send ``how``; return the exit code and the rest of the output."""
    process.send_signal(how)
    out, _ = await process.communicate()
    return process.returncode or 0, out.decode()


async def drive_until(
    publisher: Any, twist: Any, odometry: asyncio.Queue[Any], done: Callable[[Any], bool]
) -> Any:
    """Send ``twist`` (as a teleop would, each time odometry comes) until ``done(odom)``."""
    while True:
        publisher.publish(twist)
        odom = await odometry.get()
        if done(odom):
            return odom


def forward(v: float) -> Any:
    twist = Twist()
    twist.linear.x = v
    return twist


@pytest.mark.asyncio
async def test_a_plain_rclpy_node_drives_the_sim_node_and_reads_its_sensors(
    plain: Callable[..., PlainNode],
) -> None:
    teleop = plain("teleop")
    odometry = teleop.inbox("/robot1/odom", Odometry)
    ranges = teleop.inbox("/robot1/ir_front_left", Range, qos_profile_sensor_data)
    bumper = teleop.inbox("/robot1/bumper", Bool)
    battery = teleop.inbox("/robot1/battery_state", BatteryState)
    cmd_vel, matched = teleop.publisher("/robot1/cmd_vel", Twist)
    async with asyncio.timeout(DEADLINE), sim_node("--namespace", "/robot1") as process:
        await matched.wait()
        graph = teleop.node.get_topic_names_and_types
        expected = {f"/robot1/{topic}": [kind] for topic, kind in TOPICS.items()}
        await wait_for(lambda: all(dict(graph()).get(t) == k for t, k in expected.items()))
        first = await odometry.get()
        assert (first.header.frame_id, first.child_frame_id) == ("odom", "base_link")
        moved = await drive_until(
            cmd_vel, forward(0.2), odometry, lambda o: o.pose.pose.position.x > 0.1
        )
        assert moved.twist.twist.linear.x == pytest.approx(0.2, abs=0.02)
        # No more cmd_vel: the base's timeout stops the wheels.
        await next_where(odometry, lambda o: abs(o.twist.twist.linear.x) < 0.005)
        ray = await ranges.get()
        assert (ray.header.frame_id, ray.radiation_type) == ("ir_front_left", Range.INFRARED)
        assert ray.max_range == pytest.approx(0.4)
        assert ray.range == math.inf or 0.0 <= ray.range < ray.max_range
        assert (await bumper.get()).data is False
        assert 0.0 < (await battery.get()).percentage <= 1.0
        code, out = await stop(process, signal.SIGINT)
    assert code == 0
    assert out == "sim-node /robot1/sim_node stopped\n"


@pytest.mark.asyncio
async def test_two_sim_nodes_under_two_namespaces_are_driven_apart(
    plain: Callable[..., PlainNode],
) -> None:
    station = plain("operator_station")
    odom1 = station.inbox("/robot1/odom", Odometry)
    odom2 = station.inbox("/robot2/odom", Odometry)
    cmd1, matched = station.publisher("/robot1/cmd_vel", Twist)
    async with (
        asyncio.timeout(DEADLINE),
        sim_node("--namespace", "/robot1") as one,
        sim_node("--namespace", "/robot2", "--seed", "2") as two,
    ):
        await matched.wait()
        await drive_until(cmd1, forward(0.25), odom1, lambda o: o.pose.pose.position.x > 0.1)
        while not odom2.empty():  # the latest of robot2, however many came meanwhile
            still = odom2.get_nowait()
        still = await odom2.get()
        assert abs(still.pose.pose.position.x) < 0.001
        assert [await stop(one, signal.SIGTERM), await stop(two, signal.SIGTERM)] == [
            (0, "sim-node /robot1/sim_node stopped\n"),
            (0, "sim-node /robot2/sim_node stopped\n"),
        ]


@pytest.mark.asyncio
async def test_faster_than_real_time_publishes_clock_and_stamps_with_it(
    plain: Callable[..., PlainNode],
) -> None:
    listener = plain("listener")
    clock = listener.inbox("/clock", Clock)
    odometry = listener.inbox("/fast/odom", Odometry)
    async with (
        asyncio.timeout(DEADLINE),
        sim_node("--namespace", "/fast", "--rate", "4") as process,
    ):
        first = (await clock.get()).clock
        later = await next_where(clock, lambda c: c.clock.sec >= first.sec + 2)
        assert later.clock.sec < 1000  # simulated seconds since the node started, not the epoch
        odom = await odometry.get()
        assert odom.header.stamp.sec < 1000
        code, _ = await stop(process, signal.SIGINT)
    assert code == 0


def test_bad_options_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim-node", "--rate", "0"]) == 2
    assert "argument --rate: expected a positive number, got '0'" in capsys.readouterr().err
    assert main(["sim-node", "--stall-timeout", "inf"]) == 2
    assert (
        "argument --stall-timeout: expected a positive number, got 'inf'" in capsys.readouterr().err
    )
    assert main(["sim-node", "--namespace", "/robot 1"]) == 1
    assert capsys.readouterr().err.endswith(
        "pyrobots-aio: error: ROS 2 rejects the namespace '/robot 1': Invalid namespace: "
        "namespace must not contain characters other than alphanumerics, '_', or '/':\n"
        "  '/robot 1'\n         ^\n"
    )


@pytest.mark.asyncio
async def test_ticks_caught_up_after_a_stop_are_stamped_when_the_world_was_so(
    plain: Callable[..., PlainNode],
) -> None:
    """A sim-node held up (here by SIGSTOP, on a busy machine by the scheduler) catches up.

    Each tick of the burst is stamped with the simulated time it stands for, not
    with the moment it is published: between two messages the robot moved no
    farther than its speed over their stamps (what `Ros2Robot`'s reset check trusts).
    """
    teleop = plain("teleop")
    odometry = teleop.inbox("/lagging/odom", Odometry, 10_000)
    cmd_vel, matched = teleop.publisher("/lagging/cmd_vel", Twist)
    options = ("--namespace", "/lagging", "--rate", "4", "--cmd-timeout", "100")
    async with asyncio.timeout(DEADLINE), sim_node(*options) as process:
        await matched.wait()
        cmd_vel.publish(forward(0.2))
        await next_where(odometry, lambda o: o.twist.twist.linear.x > 0.19)
        process.send_signal(signal.SIGSTOP)
        await asyncio.sleep(0.5)  # two simulated seconds to catch up
        process.send_signal(signal.SIGCONT)
        seen = [await odometry.get()]
        end = _seconds(seen[0]) + 4.0
        while _seconds(seen[-1]) < end:
            seen.append(await odometry.get())
        code, _ = await stop(process, signal.SIGINT)
    assert code == 0
    for before, after in itertools.pairwise(seen):
        elapsed = _seconds(after) - _seconds(before)
        assert elapsed > 0
        moved = after.pose.pose.position.x - before.pose.pose.position.x
        speed = max(before.twist.twist.linear.x, after.twist.twist.linear.x)
        assert moved <= speed * elapsed + 1e-4


def _seconds(odom: Any) -> float:
    return float(odom.header.stamp.sec + odom.header.stamp.nanosec * 1e-9)


def test_each_robot_gets_the_stall_timeout_and_control_rate_given() -> None:
    options = parser().parse_args(
        ["sim-node", "--robots", "2", "--stall-timeout", "20", "--control-rate", "25"]
    )
    robots = [robot for robot, _ in sim_robots(options)]
    assert [robot.stall_timeout for robot in robots] == [20.0, 20.0]
    assert [robot.control_period for robot in robots] == [0.04, 0.04]
    assert parser().parse_args(["sim-node"]).stall_timeout == STALL_TIMEOUT
