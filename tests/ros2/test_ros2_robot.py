"""`Ros2Robot` against plain rclpy nodes written here: odometry in, ``cmd_vel`` out, staleness.

A plain node plays the robot's driver: it publishes ``Odometry`` and the
sensors' ``Bool`` at 50 Hz from an rclpy timer on its own thread, and
listens to ``cmd_vel``; the test reads what `Ros2Robot` makes of them.
"""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, assert_stale_error, next_where, require_rclpy

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from std_msgs.msg import Bool  # noqa: E402

from pyrobots_aio import MotionError, Ros2Error, Ros2NameError  # noqa: E402
from pyrobots_aio.motion import SENSORS  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

FLAGS = ("bumper", "bumper_left", "bumper_right", "docked")


class Driver:
    """A plain rclpy robot driver: odometry and flags at 50 Hz (while ``running``), cmd_vel in."""

    def __init__(self, node: PlainNode, namespace: str, odom_topic: str = "odom") -> None:
        self.pose = (1.0, 2.0, 0.5)
        self.running = True
        rclpy_node = node.node
        self.odom = rclpy_node.create_publisher(Odometry, f"{namespace}/{odom_topic}", 10)
        self.flags = {k: rclpy_node.create_publisher(Bool, f"{namespace}/{k}", 10) for k in FLAGS}
        self.cmd_vel = node.inbox(f"{namespace}/cmd_vel", Twist)
        self.timer = rclpy_node.create_timer(0.02, self._publish)

    def _publish(self) -> None:  # on the plain node's thread
        if not self.running:
            return
        odom = Odometry()
        x, y, yaw = self.pose
        odom.pose.pose.position.x, odom.pose.pose.position.y = x, y
        odom.pose.pose.orientation.z = math.sin(yaw / 2)
        odom.pose.pose.orientation.w = math.cos(yaw / 2)
        odom.twist.twist.linear.x = 0.1
        self.odom.publish(odom)
        for key, publisher in self.flags.items():
            publisher.publish(Bool(data=key == "docked"))


def bare(namespace: str, **options: Any) -> Ros2Robot:
    """A `Ros2Robot` with no IR and no cliff sensors (the plain driver has none)."""
    flags = [sensor for sensor in SENSORS if sensor.key in FLAGS]
    return Ros2Robot(namespace=namespace, sensors=flags, **options)


@pytest.mark.asyncio
async def test_plain_odometry_moves_the_pose_and_drive_reaches_a_plain_twist_subscriber(
    plain: Callable[..., PlainNode],
) -> None:
    driver = Driver(plain("driver"), "/plain", odom_topic="odometry")
    robot = bare("/plain", topics={"odom": "odometry"}, odom_in_map=(1.0, 0.0, math.pi / 2))
    async with asyncio.timeout(DEADLINE), robot:
        assert robot.odom_pose() == pytest.approx((1.0, 2.0, 0.5))
        assert robot.map_pose() == pytest.approx((-1.0, 1.0, 0.5 + math.pi / 2))
        me = robot.poses.inframe("base_link", "odom")
        assert (me.x, me.y) == pytest.approx((1.0, 2.0))
        assert (robot.state.v, robot.state.docked, robot.state.bumper) == (0.1, True, False)
        driver.pose = (1.2, 2.0, 0.25)  # (farther at once would be a reset: test_ros2_resets)
        await robot.sleep(0.2)
        assert robot.odom_pose() == pytest.approx((1.2, 2.0, 0.25))
        assert robot.control_period == pytest.approx(0.02, rel=0.25)
        robot.drive(0.2, -0.1)
        twist = await next_where(driver.cmd_vel, lambda t: t.linear.x != 0.0)
        assert (twist.linear.x, twist.angular.z) == (0.2, -0.1)
        for _ in range(3):  # re-sent with each odometry message, while it holds
            twist = await driver.cmd_vel.get()
            assert (twist.linear.x, twist.angular.z) == (0.2, -0.1)
        robot.stop()
        await next_where(driver.cmd_vel, lambda t: (t.linear.x, t.angular.z) == (0.0, 0.0))
        await robot.sleep(0.2)
        assert driver.cmd_vel.empty()  # a stopped base is told once


@pytest.mark.asyncio
async def test_stale_odometry_stops_the_base_and_refuses_motion_until_it_comes_back(
    plain: Callable[..., PlainNode],
) -> None:
    driver = Driver(plain("driver"), "/fading")
    async with asyncio.timeout(DEADLINE), bare("/fading", odom_timeout=0.3) as robot:
        assert robot.state.odom_stale is False
        turn = robot.rotate_angle(3.0)  # odometry never turns: it waits for its ticks
        await next_where(driver.cmd_vel, lambda t: t.angular.z != 0.0)
        driver.running = False
        with pytest.raises(MotionError) as caught:
            await turn
        assert_stale_error(caught.value, "/fading", 0.3)
        assert robot.state.odom_stale is True
        age = robot.odom_age()
        assert age is not None
        assert age >= 0.3
        await next_where(driver.cmd_vel, lambda t: (t.linear.x, t.angular.z) == (0.0, 0.0))
        with pytest.raises(MotionError, match="is stale"):
            robot.drive(0.1, 0.0)
        with pytest.raises(MotionError, match="is stale"):
            await robot.drive_distance(0.5)
        robot.stop()  # allowed, and nothing more is sent
        await robot.sleep(0.2)
        assert driver.cmd_vel.empty()
        driver.running = True
        await robot.wait("odom_stale", becomes=False)
        robot.drive(0.1, 0.0)
        await next_where(driver.cmd_vel, lambda t: t.linear.x == 0.1)
        assert robot.handles() == []


@pytest.mark.asyncio
async def test_a_robot_whose_topics_stay_silent_says_which_and_leaves_nothing_behind() -> None:
    robot = bare("/nobody", connect_timeout=0.5)
    with pytest.raises(Ros2Error) as caught:
        async with robot:
            pytest.fail("entered without a driver")
    assert str(caught.value).startswith(
        "no message in 0.5 s on /nobody/odom, /nobody/bumper, /nobody/bumper_left, "
        "/nobody/bumper_right, /nobody/docked: is the robot's driver (or 'pyrobots-aio "
        "sim-node --namespace /nobody') running in domain "
    )
    assert not robot.ros2.is_running


@pytest.mark.parametrize(
    ("options", "error", "message"),
    [
        (
            {"namespace": "/robot 1"},
            Ros2NameError,
            "ROS 2 rejects the namespace '/robot 1': Invalid namespace: namespace must not "
            "contain characters other than alphanumerics, '_', or '/':\n  '/robot 1'\n         ^",
        ),
        (
            {"name": "robot-1"},
            Ros2NameError,
            "ROS 2 rejects the node name 'robot-1': Invalid node name: node name must not "
            "contain characters other than alphanumerics or '_':\n  'robot-1'\n        ^",
        ),
        (
            {"topics": {"odom": "odom filtered"}},
            Ros2NameError,
            "ROS 2 rejects the odom topic name 'odom filtered': Invalid topic name: topic name "
            "must not contain characters other than alphanumerics, '_', '~', '{', or '}':\n"
            "  'odom filtered'\n       ^",
        ),
        (
            {"topics": {"odometry": "odom"}},
            ValueError,
            "unknown topic roles ['odometry'] in topics=; known roles: ['bumper', ",
        ),
        ({"odom_timeout": 0}, ValueError, "odom_timeout must be a positive number of seconds"),
        (
            {"odom_in_map": (0.0, 0.0)},
            ValueError,
            "odom_in_map must be a planar pose (x, y, yaw) of finite numbers, got (0.0, 0.0)",
        ),
        (
            {"dock": (0.0, math.nan, 0.0)},
            ValueError,
            "dock must be a planar pose (x, y, yaw) of finite numbers, got (0.0, nan, 0.0)",
        ),
        (
            {"sensors": ["ir_left"]},
            TypeError,
            "sensors must be Sensor records (pyrobots_aio.motion.Sensor), got 'ir_left'",
        ),
        (
            {"profile": "create2"},
            ValueError,
            "unknown ROS 2 profile 'create2'; known profiles: ['create3', 'standard']",
        ),
    ],
    ids=[
        "namespace",
        "name",
        "topic",
        "role",
        "timeout",
        "odom_in_map",
        "dock",
        "sensor",
        "profile",
    ],
)
def test_bad_options_are_refused_with_the_reason(
    options: dict[str, Any], error: type[Exception], message: str
) -> None:
    with pytest.raises(error) as caught:
        Ros2Robot(**options)
    assert str(caught.value).startswith(message)
