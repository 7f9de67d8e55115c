"""A driver that restarts mid-motion: its odometry jumps back, and the motion does not act on it.

A plain rclpy driver integrates ``cmd_vel`` into its odometry (50 Hz, its
own thread) and restarts during a ``drive_distance``, 1.2 m along: its pose
starts again from zero. The robot logs the reset, counts it, and the drive
goes on to cover its distance, as the driver's own count of metres says.
"""

from __future__ import annotations

import asyncio
import logging
import math
import re
from typing import TYPE_CHECKING

import pytest
from ros2_support import DEADLINE, PEER_SILENCE, require_rclpy

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from std_msgs.msg import Bool  # noqa: E402

from pyrobots_aio.motion import SENSORS  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402
from pyrobots_aio.ros2._profiles import Odometry as Reading  # noqa: E402
from pyrobots_aio.ros2._resets import OdometryResets  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

FLAGS = ("bumper", "bumper_left", "bumper_right", "docked")


TICK = 0.02  # seconds: the driver's odometry rate, 50 Hz


class RestartingDriver:
    """A plain driver whose odometry integrates cmd_vel, and restarts from zero past ``restart_at``.

    Each tick moves it by the last command for one tick (`TICK`), if a command came since the
    tick before: a base whose commands hold one tick, which the robot renews at each odometry
    message while it drives. So its wheels go no farther than the robot commanded, however a
    loaded machine holds either thread up, and it restarts where it says (``restarted_from``).
    """

    def __init__(self, node: PlainNode, namespace: str, restart_at: float) -> None:
        self.x, self.travelled, self.restart_at = 1.0, 0.0, restart_at
        self.command: float | None = None  # the rclpy thread's alone: the executor's one thread
        self.restarted_from: float | None = None
        """The last odometry before the restart."""
        self.restarted_to: float | None = None
        """The first odometry after it."""
        rclpy_node = self.node = node.node
        self.odom = rclpy_node.create_publisher(Odometry, f"{namespace}/odom", 10)
        self.flags = {k: rclpy_node.create_publisher(Bool, f"{namespace}/{k}", 10) for k in FLAGS}
        rclpy_node.create_subscription(Twist, f"{namespace}/cmd_vel", self._command, 10)
        self.timer = rclpy_node.create_timer(TICK, self._tick)

    def _command(self, twist: Twist) -> None:
        self.command = twist.linear.x

    def _tick(self) -> None:  # on the plain node's thread
        v, self.command = self.command or 0.0, None
        if self.restarted_from is not None and self.restarted_to is None:
            self.x = 0.0  # the restarted driver's odometry starts again at its origin
        self.x += v * TICK
        self.travelled += abs(v * TICK)
        if self.restarted_from is None and self.x > self.restart_at:
            self.restarted_from = self.x  # published: the next tick restarts
        elif self.restarted_from is not None and self.restarted_to is None:
            self.restarted_to = self.x
        odom = Odometry()
        odom.header.stamp = self.node.get_clock().now().to_msg()
        odom.pose.pose.position.x, odom.pose.pose.orientation.w = self.x, 1.0
        odom.twist.twist.linear.x = v
        self.odom.publish(odom)
        for publisher in self.flags.values():
            publisher.publish(Bool(data=False))


@pytest.mark.asyncio
async def test_a_driver_restarting_mid_drive_is_a_reset_and_the_drive_covers_its_distance(
    plain: Callable[..., PlainNode], caplog: pytest.LogCaptureFixture
) -> None:
    driver = RestartingDriver(plain("restarting_driver"), "/restarts", restart_at=1.2)
    flags = [sensor for sensor in SENSORS if sensor.key in FLAGS]
    # Odometry waited for PEER_SILENCE (not 0.5 s): a loaded machine holds the driver's
    # thread, or the loop, up for longer; staleness has tests of its own.
    robot = Ros2Robot(
        namespace="/restarts", sensors=flags, dock=(-5.0, 0.0, 0.0), odom_timeout=PEER_SILENCE
    )
    async with asyncio.timeout(DEADLINE), robot:
        assert robot.state.odom_resets == 0
        done = await robot.drive_distance(0.5, speed=0.2)
        assert robot.state.odom_resets == 1
        assert robot.odom_pose()[0] == pytest.approx(1.5, abs=0.05)  # the pose went on
    assert done == pytest.approx(0.5, abs=0.05)
    assert driver.travelled == pytest.approx(0.5, abs=0.05)  # and so did the wheels
    [warning] = [r.getMessage() for r in caplog.records if "was reset" in r.getMessage()]
    before, after = f"{driver.restarted_from:.3f}", f"{driver.restarted_to:.3f}"
    assert re.fullmatch(
        rf"odometry on /restarts/odom was reset \(a driver restart\?\): it jumped from "
        rf"\({before}, 0\.000, 0\.000\) to \({after}, 0\.000, 0\.000\), its stamp from "
        rf"\d+\.\d{{3}} to \d+\.\d{{3}} s; the robot's pose goes on from \({before}, 0\.000, "
        r"0\.000\), and motions do not act on the jump",
        warning,
    ), warning
    assert 1.2 < driver.restarted_from <= 1.2 + 0.2 * TICK + 1e-9  # mid-drive, at 1.2 m
    assert driver.restarted_to <= 0.2 * TICK + 1e-9  # back at its origin


def reading(x: float, yaw: float, stamp: float) -> Reading:
    return Reading((x, 0.0, yaw), 0.0, 0.0, stamp)


def test_a_stamp_going_back_or_a_turn_too_far_is_a_reset_and_the_pose_goes_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    resets = OdometryResets("/odom", horizon=1.0)
    pose = resets.pose(reading(2.0, 0.5, 10.0), (0.0, 0.0, 0.0), 0.0)
    assert pose == (2.0, 0.0, 0.5)
    pose = resets.pose(reading(2.01, 0.52, 10.02), pose, 0.02)  # an ordinary step: no reset
    assert pose == pytest.approx((2.01, 0.0, 0.52))
    pose = resets.pose(reading(2.02, 0.53, 1.0), pose, 0.04)  # the stamp went back: a reset
    assert pose == pytest.approx((2.01, 0.0, 0.52))
    pose = resets.pose(reading(2.12, 0.53, 1.02), pose, 0.06)  # then on, in the rebased frame
    # (0.1 m along the raw frame's x, which is turned by -0.01 rad in the robot's)
    assert pose == pytest.approx((2.01 + 0.1 * math.cos(0.01), -0.1 * math.sin(0.01), 0.52))
    pose = resets.pose(reading(2.12, -1.0, 1.04), pose, 0.08)  # turned 1.5 rad in 20 ms: reset
    assert pose[2] == pytest.approx(0.52)
    assert resets.count == 2
    assert len(caplog.records) == 2


def test_a_jump_that_the_reported_speeds_explain_is_no_reset() -> None:
    resets = OdometryResets("/odom", horizon=1.0)
    turning = Reading((0.3, 0.0, 0.25), 0.0, 0.9, 80.5)
    resets.pose(turning, (0.0, 0.0, 0.0), 0.0)
    later = Reading((0.3, 0.0, 0.8), 0.0, 0.9, 81.1)  # 0.55 rad in 0.6 s at 0.9 rad/s
    assert resets.pose(later, (0.3, 0.0, 0.25), 0.6) == later.pose
    unstamped = OdometryResets("/odom", horizon=1.0)
    unstamped.pose(Reading((0.0, 0.0, 0.0), 0.3, 0.0), (0.0, 0.0, 0.0), 10.0)
    farther = Reading((0.4, 0.0, 0.0), 0.3, 0.0)  # 0.4 m in 1.5 s (counted 1 s) at 0.3 m/s
    assert unstamped.pose(farther, (0.0, 0.0, 0.0), 11.5) == farther.pose
    stopped = Reading((0.0, 0.0, 0.0), 0.0, 0.0)  # and 0.4 m back at rest: a reset
    assert unstamped.pose(stopped, farther.pose, 11.52) == farther.pose
    assert (resets.count, unstamped.count) == (0, 1)
