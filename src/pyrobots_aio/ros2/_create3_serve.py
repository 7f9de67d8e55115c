"""The Create 3's action servers, served over any `DriveBase`'s own motion actions.

``undock``, ``dock``, ``drive_distance``, ``rotate_angle`` and
``navigate_to_position`` (``CREATE3_ACTIONS``), each a served action
(`Ros2Node.serve_action`) whose goal runs the base's motion action of the
same meaning: goal, feedback (at each control tick), result (the pose in
``odom``), cancel (the motion action is cancelled, so the base stops, and the
goal ends CANCELED). A goal that cannot run (a speed that is not positive,
the emergency stop latched) is rejected.

As on a Create 3 with its reflexes disabled, a bump does not end a goal: the
base keeps to its goal, and the program that sent it cancels it if it wants
to (as Create 3 programs do, on ``hazard_detection``); a base that pushes
against an obstacle without moving stalls, and its goal is aborted.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ._create3 import create3_action
from ._profiles import _yaw
from ._rclpy import rclpy_module

if TYPE_CHECKING:
    from collections.abc import Coroutine, Mapping

    from ..actions import ActionHandle
    from ..motion import DriveBase
    from ._node import Ros2Node
    from ._serve import Ros2ActionServer

__all__ = ["serve_create3"]

Feedback = Callable[..., None]


def _pose(robot: DriveBase) -> Any:
    """The base's odometry pose as a ``geometry_msgs/PoseStamped`` in ``odom``, stamped now."""
    pose = rclpy_module("geometry_msgs.msg").PoseStamped()
    node: Ros2Node = robot.ros2
    pose.header.stamp, pose.header.frame_id = node.node.get_clock().now().to_msg(), "odom"
    x, y, yaw = robot.odom_pose()
    pose.pose.position.x, pose.pose.position.y = x, y
    pose.pose.orientation.z, pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return pose


async def _with_feedback(
    robot: DriveBase,
    motion: ActionHandle[Any],
    feedback: Feedback,
    fields: Callable[[], Mapping[str, Any]],
) -> Any:
    """Await ``motion``, sending ``feedback(**fields())`` at each control tick meanwhile."""
    ticks = robot.state.subscribe(lambda _: feedback(**fields()), keys="v")
    try:
        return await motion
    finally:
        ticks.close()


async def _undock(robot: DriveBase, _goal: Any, _feedback: Feedback) -> Any:
    await robot.undock()
    return create3_action("undock").Result(is_docked=bool(robot.state["docked"]))


async def _dock(robot: DriveBase, _goal: Any, feedback: Feedback) -> Any:
    feedback(sees_dock=True)  # the dock's place is known: it is always in sight
    await robot.dock()
    return create3_action("dock").Result(is_docked=bool(robot.state["docked"]))


async def _drive_distance(robot: DriveBase, goal: Any, feedback: Feedback) -> Any:
    x0, y0, _ = robot.odom_pose()

    def remaining() -> Mapping[str, float]:
        x, y, _ = robot.odom_pose()
        return {"remaining_travel_distance": abs(goal.distance) - math.hypot(x - x0, y - y0)}

    motion = robot.drive_distance(goal.distance, goal.max_translation_speed)
    await _with_feedback(robot, motion, feedback, remaining)
    return create3_action("drive_distance").Result(pose=_pose(robot))


async def _rotate_angle(robot: DriveBase, goal: Any, feedback: Feedback) -> Any:
    motion = robot.rotate_angle(goal.angle, goal.max_rotation_speed)
    start = robot.odom_pose()[2]
    turned = [0.0, start]  # the turn so far, and the last yaw (the turn is not wrapped)

    def remaining() -> Mapping[str, float]:
        yaw = robot.odom_pose()[2]
        turned[0] += math.remainder(yaw - turned[1], math.tau)
        turned[1] = yaw
        return {"remaining_angle_travel": goal.angle - turned[0]}

    await _with_feedback(robot, motion, feedback, remaining)
    return create3_action("rotate_angle").Result(pose=_pose(robot))


async def _navigate(robot: DriveBase, goal: Any, feedback: Feedback) -> Any:
    kinds = create3_action("navigate_to_position").Feedback
    target = goal.goal_pose.pose
    frame = goal.goal_pose.header.frame_id or "odom"
    tx, ty = target.position.x, target.position.y
    yaw = _yaw(target.orientation)
    if not goal.achieve_goal_heading:  # the heading it arrives with: the way there
        there = robot.poses.inframe((tx, ty, 0.0, frame), "base_link")
        yaw = robot.poses.euler(robot.poses.inframe("base_link", frame))[2] + math.atan2(
            there.y, there.x
        )
    pose = {"x": tx, "y": ty, "qz": math.sin(yaw / 2), "qw": math.cos(yaw / 2), "frame": frame}

    def remaining() -> Mapping[str, Any]:
        here = robot.poses.inframe("base_link", frame)
        distance = math.hypot(tx - here.x, ty - here.y)
        angle = math.remainder(yaw - robot.poses.euler(here)[2], math.tau)
        state = (
            kinds.DRIVING_TO_GOAL_POSITION
            if distance > 0.01
            else kinds.ROTATING_TO_GOAL_ORIENTATION
        )
        return {
            "navigate_state": state,
            "remaining_travel_distance": distance,
            "remaining_angle_travel": angle,
        }

    motion = robot.navigate_to(pose, goal.max_translation_speed)
    await _with_feedback(robot, motion, feedback, remaining)
    return create3_action("navigate_to_position").Result(pose=_pose(robot))


_SERVED: dict[str, Callable[[DriveBase, Any, Feedback], Coroutine[Any, Any, Any]]] = {
    "undock": _undock,
    "dock": _dock,
    "drive_distance": _drive_distance,
    "rotate_angle": _rotate_angle,
    "navigate_to_position": _navigate,
}


def serve_create3(robot: DriveBase, ros2: Ros2Node) -> list[Ros2ActionServer]:
    """Serve the Create 3's action servers on ``ros2`` (relative names), over ``robot``'s motion.

    Example:
        >>> servers = serve_create3(robot, robot.ros2)  # doctest: +SKIP
        >>> [s.name for s in servers]  # doctest: +SKIP
        ['/undock', '/dock', '/drive_distance', '/rotate_angle', '/navigate_to_position']
    """
    return [ros2.serve_action(name, create3_action(name), fn) for name, fn in _SERVED.items()]
