"""Service calls and action goals, awaited on the event loop.

Both first wait for their server to appear in the ROS graph (rclpy would
send into the void otherwise), then await rclpy's futures through the ROS
thread. Cancelling a call drops its pending request; cancelling a goal's
pyrobots_aio action asks the server to cancel the goal and waits for its
final answer — bounded, as every cleanup is, by the robot's ``cancel_grace``.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Any

from .._exceptions import GoalError, GoalRejectedError

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from ..robot import Robot
    from ._thread import RosThread

_log = logging.getLogger("pyrobots_aio.ros2")

# action_msgs/msg/GoalStatus codes (fixed by the ROS 2 action design)
_SUCCEEDED, _CANCELED, _ABORTED = 4, 5, 6
_STATUS_NAMES = {_CANCELED: "canceled", _ABORTED: "aborted"}


async def call_service(thread: RosThread, client: Any, service: str, request: Any) -> Any:
    """Send ``request`` once the server is there; return the response. Cancellable."""
    await thread.wait_until(client.service_is_ready)
    future = client.call_async(request)
    try:
        return await thread.wrap(future)
    except asyncio.CancelledError:
        client.remove_pending_request(future)
        _log.debug("call to %s cancelled; its request is dropped", service)
        raise


def feedback_writer(
    thread: RosThread, robot: Robot, mapping: Callable[[Any], Mapping[str, object] | None] | None
) -> Callable[[Any], None] | None:
    """The rclpy feedback callback that writes each feedback to ``robot.state``, on the loop."""
    if mapping is None:
        return None

    def write(feedback: Any) -> None:
        try:
            values = mapping(feedback)
            if values:
                robot.state.update(values)
        except Exception:  # logged; the goal goes on
            _log.exception("a goal's feedback could not be written to the state")

    return lambda message: thread.to_loop(write, message.feedback)


async def run_goal(
    robot: Robot,
    thread: RosThread,
    client: Any,
    *,
    action_name: str,
    goal: Any,
    feedback: Callable[[Any], None] | None,
) -> Any:
    """The body of a goal's action: send, wait for the result, cancel the goal if cancelled."""
    await thread.wait_until(client.server_is_ready)
    sending = thread.wrap(client.send_goal_async(goal, feedback_callback=feedback))
    try:
        goal_handle = await asyncio.shield(sending)
    except asyncio.CancelledError:
        goal_handle = await sending  # the server's answer to the goal, then cancel it
        if goal_handle.accepted:
            await _cancel(
                thread, goal_handle, thread.wrap(goal_handle.get_result_async()), action_name
            )
        raise
    if not goal_handle.accepted:
        msg = f"the action server of {action_name!r} rejected the goal {goal!r}"
        raise GoalRejectedError(action_name, "rejected", msg)
    result = thread.wrap(goal_handle.get_result_async())
    try:
        response = await asyncio.shield(result)
    except asyncio.CancelledError:
        await _cancel(thread, goal_handle, result, action_name)
        raise
    if response.status == _SUCCEEDED:
        return response.result
    status = _STATUS_NAMES.get(response.status, f"status {response.status}")
    msg = f"the goal on {action_name!r} ended {status} by its server: {response.result!r}"
    raise GoalError(action_name, status, msg)


async def _cancel(
    thread: RosThread, goal_handle: Any, result: asyncio.Future[Any], name: str
) -> None:
    """Ask the server to cancel the goal, then wait for the goal's final status."""
    answer = await thread.wrap(goal_handle.cancel_goal_async())
    if not answer.goals_canceling:
        _log.warning(
            "the action server of %s did not accept to cancel the goal "
            "(cancel response code %s, no goal canceling); it may go on",
            name,
            answer.return_code,
        )
        return
    response = await result
    _log.debug("goal on %s cancelled; final status %s", name, response.status)
