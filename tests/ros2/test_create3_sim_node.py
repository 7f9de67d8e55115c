"""``sim-node --profile create3``: the Create 3's topics and action servers, for plain rclpy."""

from __future__ import annotations

import asyncio
import contextlib
import math
import signal
from typing import TYPE_CHECKING, Any

import pytest
import pytest_asyncio
from ros2_support import (
    DEADLINE,
    PEER_SILENCE,
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
    HazardDetection,
    HazardDetectionVector,
    IrIntensityVector,
)
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data  # noqa: E402
from test_sim_node import sim_node, stop  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

NS = "/create3"
RATE = 4.0
TOPICS = {
    "hazard_detection": "irobot_create_msgs/msg/HazardDetectionVector",
    "ir_intensity": "irobot_create_msgs/msg/IrIntensityVector",
    "dock_status": "irobot_create_msgs/msg/DockStatus",
    "odom": "nav_msgs/msg/Odometry",
    "cmd_vel": "geometry_msgs/msg/Twist",
    "battery_state": "sensor_msgs/msg/BatteryState",
}


DEEP = QoSProfile(depth=10_000, reliability=ReliabilityPolicy.BEST_EFFORT)
"""A best-effort subscription that keeps what its thread has not taken yet."""


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
        # Odometry: the newest only (a test that waits for the base to stop wants what it
        # does now, not a backlog). Hazards: every one, best effort as the node publishes
        # them, with a deep reader history: at --rate 4 a 1.5-simulated-second bump is 0.4 s
        # of messages, which the sensor-data profile's 5 would let a reader thread held up
        # that long (a loaded machine) overwrite unseen.
        self.odometry = node.inbox(f"{NS}/odom", Odometry, qos_profile_sensor_data)
        self.hazards = node.inbox(f"{NS}/hazard_detection", HazardDetectionVector, DEEP)
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


@pytest_asyncio.fixture
async def goals(plain: Callable[..., PlainNode]) -> Goals:
    """A plain Create 3 program's action clients (its node is closed with the test)."""
    return Goals(plain("create3_program", threads=2, spin=False))


def create3_node(
    *options: str,
) -> contextlib.AbstractAsyncContextManager[asyncio.subprocess.Process]:
    """A ``sim-node --profile create3`` four times faster than real time (and ``options``)."""
    return sim_node("--namespace", NS, "--profile", "create3", "--rate", str(RATE), *options)


def seconds(stamp: Any) -> float:
    return float(stamp.sec + stamp.nanosec * 1e-9)


def bumped(hazards: HazardDetectionVector) -> bool:
    return any(d.type == HazardDetection.BUMP for d in hazards.detections)


async def into_the_east_wall(goals: Goals) -> Any:
    """Undock, then drive 5 m east at 0.3 m/s: the wall is 3.4 m ahead (the goal's handle)."""
    await goals.run("undock", Undock.Goal())
    return await goals.send(
        "drive_distance", DriveDistance.Goal(distance=5.0, max_translation_speed=0.3)
    )


async def assert_stopped(odometry: asyncio.Queue[Any]) -> None:
    """The base comes to rest and stays there (a simulated second later, the same pose)."""
    while not odometry.empty():  # what came before the goal ended
        odometry.get_nowait()
    still = await next_where(
        odometry,
        lambda o: abs(o.twist.twist.linear.x) < 0.001 and abs(o.twist.twist.angular.z) < 0.001,
    )
    later = await next_where(odometry, lambda o: o.header.stamp.sec > still.header.stamp.sec)
    for axis in ("x", "y", "z", "w"):
        here = getattr(still.pose.pose.orientation, axis)
        assert getattr(later.pose.pose.orientation, axis) == pytest.approx(here, abs=1e-3)
    assert later.pose.pose.position.x == pytest.approx(still.pose.pose.position.x, abs=1e-3)
    assert later.pose.pose.position.y == pytest.approx(still.pose.pose.position.y, abs=1e-3)


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
    goals: Goals,
) -> None:
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
    goals: Goals,
) -> None:
    odometry = goals.odometry
    async with asyncio.timeout(DEADLINE), create3_node() as process:
        await goals.run("undock", Undock.Goal())
        feedback: list[Any] = []
        handle = await goals.send(
            "drive_distance", DriveDistance.Goal(distance=2.0, max_translation_speed=0.2), feedback
        )
        await wait_for(lambda: len(feedback) > 2)  # it drives
        # Stopped by the goal's end (the served goals drive the base with no cmd_vel at all).
        await cancel(goals, handle)
        latest = odometry.get_nowait() if not odometry.empty() else await odometry.get()
        assert 0.35 < latest.pose.pose.position.x < 1.0  # well short of the 2 m asked
        assert (await stop(process, signal.SIGINT))[0] == 0


async def cancel(goals: Goals, handle: Any) -> None:
    """Cancel ``handle``'s goal: the cancel is taken, the goal ends CANCELED, the base stops."""
    answer = await goals.future(handle.cancel_goal_async())
    assert len(answer.goals_canceling) == 1
    result = await goals.future(handle.get_result_async())
    assert result.status == GoalStatus.STATUS_CANCELED
    await assert_stopped(goals.odometry)


def rotation() -> RotateAngle.Goal:
    """Ten turns at 0.5 rad/s: two minutes of simulated time, cancelled long before."""
    return RotateAngle.Goal(angle=20 * math.pi, max_rotation_speed=0.5)


def navigation() -> NavigateToPosition.Goal:
    """To 3 m east of odom's origin at 5 cm/s: a minute of simulated time, cancelled before."""
    goal = NavigateToPosition.Goal(achieve_goal_heading=True, max_translation_speed=0.05)
    goal.goal_pose.header.frame_id = "odom"
    goal.goal_pose.pose.position.x, goal.goal_pose.pose.orientation.w = 3.0, 1.0
    return goal


@pytest.mark.asyncio
@pytest.mark.parametrize(
    ("name", "goal"), [("rotate_angle", rotation), ("navigate_to_position", navigation)]
)
async def test_a_cancelled_turn_or_navigation_stops_the_base_and_ends_canceled(
    goals: Goals, name: str, goal: Callable[[], Any]
) -> None:
    async with asyncio.timeout(DEADLINE), create3_node() as process:
        await goals.run("undock", Undock.Goal())
        feedback: list[Any] = []
        handle = await goals.send(name, goal(), feedback)
        await wait_for(lambda: len(feedback) > 2)  # it moves
        await cancel(goals, handle)
        assert (await stop(process, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
async def test_a_bump_alone_does_not_end_a_create3_goal(goals: Goals) -> None:
    """As on a Create 3 with its reflexes disabled: the program that sent the goal ends it."""
    # A stall ends a goal that pushes: not within the test's wait (PEER_SILENCE of the wall
    # clock), however long a loaded machine holds this test up.
    stall = ("--stall-timeout", str(PEER_SILENCE * RATE))
    async with asyncio.timeout(DEADLINE), create3_node(*stall) as process:
        handle = await into_the_east_wall(goals)
        bump = seconds((await next_where(goals.hazards, bumped)).header.stamp)
        # Two simulated seconds later it still pushes, bumped, and the goal goes on.
        await next_where(
            goals.hazards, lambda h: bumped(h) and seconds(h.header.stamp) >= bump + 2.0
        )
        await cancel(goals, handle)  # it was still running: CANCELED
        assert (await stop(process, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
async def test_a_create3_goal_that_stalls_against_a_wall_is_aborted(
    goals: Goals,
) -> None:
    async with asyncio.timeout(DEADLINE), create3_node("--stall-timeout", "1.5") as process:
        handle = await into_the_east_wall(goals)
        await next_where(goals.hazards, bumped)
        result = await goals.future(handle.get_result_async())
        assert result.status == GoalStatus.STATUS_ABORTED
        await assert_stopped(goals.odometry)
        assert (await stop(process, signal.SIGINT))[0] == 0
