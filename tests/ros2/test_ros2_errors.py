"""Bad input: refused with a message that names the value, the types, and ROS 2's own reason."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest
from ros2_support import DEADLINE, require_rclpy, wait_for

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402
from test_msgs.action import Fibonacci  # noqa: E402

from pyrobots_aio import PyRobotsError, Robot, Ros2Error, Ros2NameError, TopicTypeError  # noqa: E402
from pyrobots_aio.ros2 import Ros2Node, Ros2Robot, attach_ros2  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode


def test_a_node_name_ros2_rejects_is_refused_with_its_reason() -> None:
    with pytest.raises(Ros2NameError) as caught:
        attach_ros2(Robot(), "my-node")
    assert str(caught.value) == (
        "ROS 2 rejects the node name 'my-node': Invalid node name: node name must not contain "
        "characters other than alphanumerics or '_':\n  'my-node'\n     ^"
    )
    assert isinstance(caught.value, ValueError)


def test_a_namespace_ros2_rejects_is_refused_with_its_reason() -> None:
    robot = Robot()
    with pytest.raises(Ros2NameError) as caught:
        attach_ros2(robot, "executive", namespace="/robot 1")
    assert str(caught.value) == (
        "ROS 2 rejects the namespace '/robot 1': Invalid namespace: namespace must not contain "
        "characters other than alphanumerics, '_', or '/':\n  '/robot 1'\n         ^"
    )
    assert robot.extensions == {}  # nothing attached


def test_a_relative_namespace_is_made_absolute_as_rclpy_does() -> None:
    assert Ros2Node("executive", namespace="robot1").full_name == "/robot1/executive"
    assert Ros2Node("executive", namespace="").full_name == "/executive"


def test_attaching_twice_or_to_a_running_robot_is_refused() -> None:
    robot = Robot()
    node = attach_ros2(robot, "first")
    assert robot.extensions == {"ros2": node}  # the robot's extension, not an attribute set on it
    assert robot.ros2 is node
    assert "ros2" not in vars(robot)
    with pytest.raises(PyRobotsError, match=r"has a ROS 2 node already: <Ros2Node /first stopped>"):
        attach_ros2(robot, "second")


def test_a_ros2_robot_has_its_node_already() -> None:
    robot = Ros2Robot(name="base")
    with pytest.raises(PyRobotsError, match=r"has a ROS 2 node already: <Ros2Node /base stopped>"):
        attach_ros2(robot, "second")


@pytest.mark.asyncio
async def test_attaching_to_a_running_robot_is_refused() -> None:
    async with Robot() as robot:
        with pytest.raises(
            PyRobotsError, match=r"^attach the ROS 2 node before 'async with robot:'"
        ):
            attach_ros2(robot, "late")


def test_a_node_used_before_its_robot_runs_says_so() -> None:
    ros2 = attach_ros2(Robot(), "idle")
    with pytest.raises(Ros2Error) as caught:
        ros2.subscribe("/x", Twist, "x")
    assert str(caught.value) == (
        "the ROS 2 node 'idle' is not running; use it inside 'async with robot:' "
        "(attach it with attach_ros2(robot) first)"
    )


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            {"domain_id": -1},
            "domain_id must be a non-negative integer (None: ROS_DOMAIN_ID), got -1",
        ),
        ({"stale_after": 0}, "stale_after must be a positive number of seconds, got 0"),
        ({"diagnostics_period": "1"}, "diagnostics_period must be a positive number of seconds"),
    ],
)
def test_bad_node_options_are_refused(options: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Ros2Node("executive", **options)  # type: ignore[arg-type]


@pytest.mark.asyncio
async def test_a_topic_of_another_type_on_this_node_names_both_types() -> None:
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot:
        robot.ros2.subscribe("/cmd", Twist, "cmd")
        with pytest.raises(TopicTypeError) as caught:
            robot.ros2.publisher("/cmd", Odometry)
        assert str(caught.value) == (
            "cannot publish on '/cmd' as nav_msgs/msg/Odometry: the topic carries "
            "geometry_msgs/msg/Twist; use that type, or another topic"
        )


@pytest.mark.asyncio
async def test_a_topic_another_node_publishes_with_another_type_names_both_types(
    plain: Callable[..., PlainNode],
) -> None:
    teleop = plain("teleop")
    teleop.publisher("/teleop", Twist)
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        graph = robot.ros2.node.get_topic_names_and_types
        await wait_for(lambda: "/teleop" in dict(graph()))
        with pytest.raises(TopicTypeError) as caught:
            robot.ros2.subscribe("/teleop", Odometry, {"x": "pose.pose.position.x"})
        assert str(caught.value) == (
            "cannot subscribe to '/teleop' as nav_msgs/msg/Odometry: the topic carries "
            "geometry_msgs/msg/Twist; use that type, or another topic"
        )
        assert isinstance(caught.value, TypeError)


@pytest.mark.asyncio
async def test_bad_subscriptions_and_publishers_are_refused_clearly() -> None:
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot:
        ros2 = robot.ros2
        with pytest.raises(
            Ros2NameError, match=r"^ROS 2 rejects the topic name 'cmd vel': Invalid"
        ):
            ros2.subscribe("cmd vel", Twist, "cmd")
        with pytest.raises(TypeError) as caught:
            ros2.subscribe("/x", dict, "x")
        assert str(caught.value) == (
            "<class 'dict'> is not a ROS 2 message type; pass a generated message class, "
            "such as geometry_msgs.msg.Twist"
        )
        with pytest.raises(ValueError, match="has no field") as wrong_field:
            ros2.subscribe("/odom", Odometry, {"x": "pose.position.x"})
        assert str(wrong_field.value) == (
            "nav_msgs/msg/Odometry has no field 'pose.position.x': pose has fields "
            "['covariance', 'pose']"
        )
        with pytest.raises(TypeError, match=r"^to_state must be a state key, a \{state_key"):
            ros2.subscribe("/x", Twist, 42)  # type: ignore[arg-type]
        with pytest.raises(TypeError, match=r"^subscribing to '/x' needs to_state="):
            ros2.subscribe("/x", Twist)
        pub = ros2.publisher("/cmd", Twist)
        with pytest.raises(TypeError) as wrong_type:
            pub.publish(Odometry())  # type: ignore[arg-type]
        assert str(wrong_type.value).startswith(
            "the publisher on '/cmd' sends geometry_msgs/msg/Twist, got "
            "nav_msgs.msg._odometry.Odometry: nav_msgs.msg.Odometry("
        )
        with pytest.raises(
            TypeError, match=r"^geometry_msgs.msg.Twist\(.*\) is not a ROS 2 service request; pass"
        ):
            await ros2.call("/reset", Twist())
        with pytest.raises(TypeError, match=r"^'/fib' takes a test_msgs/action/Fibonacci goal"):
            ros2.goal("/fib", Trigger.Request(), action_type=Fibonacci)
    with pytest.raises(Ros2Error, match=r"^the publisher on '/cmd' is closed"):
        pub.publish(Twist())


def test_without_rclpy_a_node_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from pyrobots_aio import Ros2UnavailableError

    monkeypatch.setitem(sys.modules, "rclpy", None)
    with pytest.raises(Ros2UnavailableError) as caught:
        attach_ros2(Robot(), "executive")
    assert str(caught.value) == (
        "the ROS 2 bridge needs rclpy, which cannot be imported (import of rclpy halted; "
        "None in sys.modules); install the ROS 2 Python wheels with: "
        'pip install "pyrobots-aio[ros2]", or source a ROS 2 install'
    )
    assert isinstance(caught.value, ImportError)
