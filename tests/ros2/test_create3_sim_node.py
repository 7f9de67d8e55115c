"""``sim-node --profile create3``: the Create 3's topics and action servers, for plain rclpy."""

from __future__ import annotations

import asyncio
import contextlib
import math
import signal
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import (
    DEADLINE,
    next_where,
    require_interfaces,
    require_rclpy,
    require_sim,
    wait_for,
)

require_rclpy()
require_sim()
require_interfaces("irobot_create_msgs")

from action_msgs.msg import GoalStatus  # noqa: E402
from irobot_create_msgs.action import (  # noqa: E402
    Dock,
    DriveDistance,
    NavigateToPosition,
    RotateAngle,
    Undock,
)
from irobot_create_msgs.msg import (  # noqa: E402
    DockStatus,
    HazardDetectionVector,
    IrIntensityVector,
)
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from test_sim_node import sim_node, stop  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

NS = "/create3"
TOPICS = {
    "hazard_detection": "irobot_create_msgs/msg/HazardDetectionVector",
    "ir_intensity": "irobot_create_msgs/msg/IrIntensityVector",
    "dock_status": "irobot_create_msgs/msg/DockStatus",
    "odom": "nav_msgs/msg/Odometry",
    "cmd_vel": "geometry_msgs/msg/Twist",
    "battery_state": "sensor_msgs/msg/BatteryState",
}


class Goals:
    """Plain rclpy action clients of the Create 3's servers; answers reach the test's loop.

    ``node`` does not spin yet: an action client made while its executor spins may be
    looked at before it is complete (rclpy's executor thread then dies on it).
    """

    def __init__(self, node: PlainNode) -> None:
        self.node = node
        self.clients = {
            name: ActionClient(node.node, kind, f"{NS}/{name}")
            for name, kind in [
                ("undock", Undock),
                ("dock", Dock),
                ("drive_distance", DriveDistance),
                ("rotate_angle", RotateAngle),
                ("navigate_to_position", NavigateToPosition),
            ]
        }
        self.odometry = node.inbox(f"{NS}/odom", Odometry, qos_profile_sensor_data)
        node.spin()

    def future(self, rclpy_future: Any) -> asyncio.Future[Any]:
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        rclpy_future.add_done_callback(
            lambda done: self.node.to_loop(future.set_result, done.result())
        )
        return future

    async def send(self, name: str, goal: Any, feedback: list[Any] | None = None) -> Any:
        client = self.clients[name]
        await wait_for(client.server_is_ready)

        def on_feedback(message: Any) -> None:
            if feedback is not None:
                self.node.to_loop(feedback.append, message.feedback)

        handle = await self.future(client.send_goal_async(goal, on_feedback))
        assert handle.accepted, f"{name} rejected {goal}"
        return handle

    async def run(self, name: str, goal: Any, feedback: list[Any] | None = None) -> Any:
        handle = await self.send(name, goal, feedback)
        return await self.future(handle.get_result_async())


def create3_node() -> contextlib.AbstractAsyncContextManager[asyncio.subprocess.Process]:
    """A ``sim-node --profile create3`` four times faster than real time."""
    return sim_node("--namespace", NS, "--profile", "create3", "--rate", "4")


@pytest.mark.asyncio
async def test_the_create3_topics_are_there_and_speak(plain: Callable[..., PlainNode]) -> None:
    user = plain("create3_user")
    hazards = user.inbox(f"{NS}/hazard_detection", HazardDetectionVector, qos_profile_sensor_data)
    ir = user.inbox(f"{NS}/ir_intensity", IrIntensityVector, qos_profile_sensor_data)
    dock = user.inbox(f"{NS}/dock_status", DockStatus, qos_profile_sensor_data)
    async with (
        asyncio.timeout(DEADLINE),
        sim_node("--namespace", NS, "--profile", "create3") as process,
    ):
        graph = user.node.get_topic_names_and_types
        expected = {f"{NS}/{topic}": [kind] for topic, kind in TOPICS.items()}
        await wait_for(lambda: all(dict(graph()).get(t) == k for t, k in expected.items()))
        assert list((await hazards.get()).detections) == []  # on its dock, nothing in the way
        readings = (await ir.get()).readings
        assert [r.header.frame_id for r in readings] == [
            "ir_intensity_side_left",
            "ir_intensity_left",
            "ir_intensity_front_left",
            "ir_intensity_front_center_left",
            "ir_intensity_front_center_right",
            "ir_intensity_front_right",
            "ir_intensity_right",
        ]
        assert (await dock.get()).is_docked
        assert (await stop(process, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
async def test_the_create3_actions_undock_drive_turn_navigate_and_dock(
    plain: Callable[..., PlainNode],
) -> None:
    goals = Goals(plain("create3_program", threads=2, spin=False))
    odometry = goals.odometry
    async with asyncio.timeout(DEADLINE), create3_node() as process:
        undocked = await goals.run("undock", Undock.Goal())
        assert undocked.status == GoalStatus.STATUS_SUCCEEDED
        assert undocked.result.is_docked is False
        feedback: list[Any] = []
        driven = await goals.run(
            "drive_distance", DriveDistance.Goal(distance=0.3, max_translation_speed=0.2), feedback
        )
        assert driven.status == GoalStatus.STATUS_SUCCEEDED
        assert driven.result.pose.header.frame_id == "odom"
        assert driven.result.pose.pose.position.x == pytest.approx(0.65, abs=0.01)
        await wait_for(lambda: len(feedback) > 2)
        remaining = [f.remaining_travel_distance for f in feedback]
        assert remaining == sorted(remaining, reverse=True)
        assert remaining[-1] < remaining[0] <= 0.3 + 1e-6  # (float32)
        turned = await goals.run(
            "rotate_angle", RotateAngle.Goal(angle=math.pi / 2, max_rotation_speed=1.0)
        )
        assert turned.status == GoalStatus.STATUS_SUCCEEDED
        orientation = turned.result.pose.pose.orientation
        assert 2 * math.atan2(orientation.z, orientation.w) == pytest.approx(math.pi / 2, abs=0.02)
        target = NavigateToPosition.Goal(achieve_goal_heading=True, max_translation_speed=0.2)
        target.goal_pose.header.frame_id = "odom"
        target.goal_pose.pose.position.x, target.goal_pose.pose.orientation.w = 0.5, 1.0
        navigated = await goals.run("navigate_to_position", target)
        assert navigated.status == GoalStatus.STATUS_SUCCEEDED
        assert navigated.result.pose.pose.position.x == pytest.approx(0.5, abs=0.02)
        docked = await goals.run("dock", Dock.Goal())
        assert docked.status == GoalStatus.STATUS_SUCCEEDED
        assert docked.result.is_docked is True
        assert odometry.qsize() > 0
        assert (await stop(process, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
async def test_a_cancelled_create3_goal_stops_the_base_and_ends_canceled(
    plain: Callable[..., PlainNode],
) -> None:
    goals = Goals(plain("create3_program", threads=2, spin=False))
    odometry = goals.odometry
    async with asyncio.timeout(DEADLINE), create3_node() as process:
        await goals.run("undock", Undock.Goal())
        feedback: list[Any] = []
        handle = await goals.send(
            "drive_distance", DriveDistance.Goal(distance=2.0, max_translation_speed=0.2), feedback
        )
        await wait_for(lambda: len(feedback) > 2)  # it drives
        answer = await goals.future(handle.cancel_goal_async())
        assert len(answer.goals_canceling) == 1
        result = await goals.future(handle.get_result_async())
        assert result.status == GoalStatus.STATUS_CANCELED
        # Stopped by the goal's end (the served goals drive the base with no cmd_vel at all).
        while not odometry.empty():  # what came before the goal ended
            odometry.get_nowait()
        still = await next_where(odometry, lambda o: abs(o.twist.twist.linear.x) < 0.001)
        later = await next_where(odometry, lambda o: o.header.stamp.sec > still.header.stamp.sec)
        assert later.pose.pose.position.x == pytest.approx(still.pose.pose.position.x, abs=1e-3)
        assert 0.35 < still.pose.pose.position.x < 1.0  # well short of the 2 m asked
        assert (await stop(process, signal.SIGINT))[0] == 0
