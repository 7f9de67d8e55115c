"""tf: sim-node broadcasts ``tf``/``tf_static``, `Ros2Robot` resolves them through ``robot.poses``.

A plain rclpy subscriber reads what sim-node broadcasts; a `Ros2Robot`
beside the same sim-node places the sensor frames where `SimRobot` (the same
model, in this process) places them. The `TfBuffer` alone is tested on
plain ``TFMessage`` values.
"""

from __future__ import annotations

import asyncio
import math
import sys
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest
from ros2_support import DEADLINE, next_where, require_interfaces, require_rclpy, sim_node_process

require_rclpy()
require_interfaces("tf2_msgs")

from geometry_msgs.msg import TransformStamped  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

from pyrobots_aio import Ros2Error, Ros2UnavailableError, UnknownFrameError  # noqa: E402
from pyrobots_aio.ros2 import Ros2Robot, TfBuffer  # noqa: E402
from pyrobots_aio.ros2._tf import tf_qos  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

SENSOR_FRAMES = (
    "ir_front_left",
    "ir_side_left",
    "cliff_front_left",
    "cliff_side_right",
    "bumper_left",
    "bumper_right",
)


def stamped(parent: str, child: str, x: float, yaw: float = 0.0) -> TransformStamped:
    edge = TransformStamped()
    edge.header.frame_id, edge.child_frame_id = parent, child
    edge.transform.translation.x = x
    edge.transform.rotation.z, edge.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return edge


def test_the_buffer_keeps_the_latest_edge_skips_placed_frames_and_refuses_cycles(
    caplog: pytest.LogCaptureFixture,
) -> None:
    buffer = TfBuffer(("odom", "base_link"))
    buffer.receive(TFMessage(transforms=[stamped("odom", "base_link", 5.0)]))
    assert buffer.frames() == frozenset()  # base_link is placed by the robot, not by tf
    buffer.receive(TFMessage(transforms=[stamped("/base_link", "laser", 0.2, math.pi / 2)]))
    buffer.receive(TFMessage(transforms=[stamped("base_link", "laser", 0.3, math.pi / 2)]))
    top, matrix = buffer.resolve("laser")
    assert top == "base_link"
    assert matrix[:3, 3].tolist() == pytest.approx([0.3, 0.0, 0.0])
    assert np.allclose(matrix[:2, :2], [[0.0, -1.0], [1.0, 0.0]])
    assert buffer.places("laser")
    buffer.receive(TFMessage(transforms=[stamped("laser", "mount", 0.1)]))
    buffer.receive(TFMessage(transforms=[stamped("odom", "laser", 1.0)]))  # reparented
    assert buffer.resolve("mount")[0] == "odom"
    for _ in range(2):
        buffer.receive(TFMessage(transforms=[stamped("mount", "laser", 0.1)]))
    refused = [r.getMessage() for r in caplog.records]
    assert refused == [
        "tf: refused the transform mount -> laser: cannot make 'laser' a child of 'mount': "
        "the frames would form a cycle laser->mount->laser"
    ]
    buffer.receive(TFMessage(transforms=[stamped("elsewhere", "camera", 0.1)]))
    assert not buffer.places("camera")  # its chain reaches no frame the robot places


@pytest.mark.asyncio
async def test_a_plain_subscriber_sees_odom_to_base_link_on_tf_with_the_odometry_stamp(
    plain: Callable[..., PlainNode],
) -> None:
    listener = plain("tf_listener")
    tf = listener.inbox("/tf", TFMessage, tf_qos(static=False))
    odometry = listener.inbox("/odom", Odometry)
    with sim_node_process():
        async with asyncio.timeout(DEADLINE):
            odom = await odometry.get()
            stamp = (odom.header.stamp.sec, odom.header.stamp.nanosec)

            def same_tick(message: Any) -> bool:
                head = message.transforms[0].header.stamp
                return (head.sec, head.nanosec) >= stamp

            message = await next_where(tf, same_tick)
            static = listener.inbox("/tf_static", TFMessage, tf_qos(static=True))  # latched
            sensors = await static.get()
    [edge] = message.transforms
    assert (edge.header.frame_id, edge.child_frame_id) == ("odom", "base_link")
    assert edge.transform.translation.x == pytest.approx(odom.pose.pose.position.x, abs=0.01)
    assert edge.transform.rotation.w == pytest.approx(odom.pose.pose.orientation.w, abs=0.01)
    parents = {e.child_frame_id: e.header.frame_id for e in sensors.transforms}
    assert set(SENSOR_FRAMES) <= set(parents)
    assert set(parents.values()) == {"base_link"}
    assert {"odom", "base_link", "dock"}.isdisjoint(parents)


@pytest.mark.asyncio
async def test_ros2_robot_poses_resolve_the_sensor_frames_as_sim_robot_does() -> None:
    from pyrobots_aio.sim import SimRobot

    sim = SimRobot()
    expected = {f: sim.poses.inframe(f, "base_link").matrix() for f in SENSOR_FRAMES}
    with sim_node_process("--namespace", "/tf_robot"):
        async with asyncio.timeout(DEADLINE), Ros2Robot(namespace="/tf_robot") as robot:
            await robot.tf.wait_for_frames(*SENSOR_FRAMES)
            for frame in SENSOR_FRAMES:
                seen = robot.poses.inframe(frame, "base_link").matrix()
                assert np.allclose(seen, expected[frame], atol=1e-3), frame
            left = robot.poses.inframe("ir_front_left", "odom")
            base = robot.poses.inframe("base_link", "odom")
            assert math.dist((left.x, left.y), (base.x, base.y)) == pytest.approx(
                math.dist(expected["ir_front_left"][:2, 3], (0.0, 0.0)), abs=1e-3
            )
            assert robot.poses.distance("bumper_left", "bumper_right") > 0.1
            with pytest.raises(UnknownFrameError) as caught:
                robot.poses.get_transform("laser")
            message = str(caught.value)
    assert message.startswith("unknown frame 'laser'; known frames: [")
    assert "'ir_front_left'" in message
    assert "'base_link'" in message


def test_without_tf2_msgs_tf_is_off_or_its_absence_says_how_to_build_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "tf2_msgs.msg", None)  # as if never built
    robot = Ros2Robot(namespace="/no_tf")
    assert robot.ros.topics.keys().isdisjoint({"tf", "tf_static"})
    with pytest.raises(Ros2Error) as caught:
        _ = robot.tf
    assert str(caught.value) == (
        "<Ros2Robot /no_tf/pyrobots_aio stopped> has no tf buffer: it exists inside 'async "
        "with' when tf2_msgs imports (build it with: pyrobots-aio ros2 interfaces build "
        "tf2_msgs) and tf is not False"
    )
    with pytest.raises(Ros2UnavailableError) as missing:
        Ros2Robot(namespace="/no_tf", tf=True)
    assert str(missing.value).startswith("tf needs the tf2_msgs interfaces, which cannot be ")
    assert str(missing.value).endswith(
        "; build them with: pyrobots-aio ros2 interfaces build tf2_msgs"
    )
