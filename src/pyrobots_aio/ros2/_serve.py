"""Actions and services served to ROS 2: each goal, each request, runs as a pyrobots_aio action.

A goal is decided on the loop: the served function starts as an action at
once, and the goal is accepted when that action got past its first step, or
rejected when it could not run (the emergency stop is latched, a
``wait=False`` resource is busy, the robot refuses one more action).
rclpy's goal callback, on the ROS thread, waits for that answer: one turn of
the loop (bounded by `DECISION_BOUND`). ROS 2's action protocol has no field
for a rejection's reason: the client sees ``accepted`` False and nothing
more; the reason is logged (a WARNING on ``pyrobots_aio.ros2``).

The goal then stays ``ACCEPTED`` while its action runs (paused too: the
protocol has no status for that; its feedback stops until it resumes), and is
executed (``EXECUTING``, then its final status) once the action is done:
rclpy runs a pending coroutine callback again at every turn of its executor,
so an execute callback that awaited the action would spin the ROS thread hot.
A ROS 2 cancel cancels the action (``ActionCancelled`` in its body); its
cleanup runs, and the goal ends ``CANCELED``. An action cancelled by anyone
else (a preemption, the robot's exit, the emergency stop, which ends every
served goal and request running, with or without resources) or failing ends
``ABORTED``; the reason is logged, and the client gets an empty result.

A service request waits for its action the same way, its response sent once
the action is done (rclpy's service callback returns at once; the response
it would send is deferred). ROS 2 services cannot refuse a request: one whose
action could not run, failed or was cancelled is answered with a *refusal*
(`refusal`): ``success`` False and the reason in ``message`` where the
response type has those fields (std_srvs' Trigger and SetBool, and the many
types that follow them), else an empty response, which its client cannot
tell from a real one. The reason is logged either way.
"""

from __future__ import annotations

import concurrent.futures
import inspect
import logging
import threading
from typing import TYPE_CHECKING, Any

from .._exceptions import Ros2Error
from ..actions import Action, ActionHandle, Outcome
from ._rclpy import rclpy_module, ros_name

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..robot import Robot
    from ._thread import RosThread

__all__ = ["DECISION_BOUND", "Ros2ActionServer", "Ros2ServiceServer"]

_log = logging.getLogger("pyrobots_aio.ros2")

DECISION_BOUND = 5.0
"""Seconds rclpy's goal callback waits for the loop to accept or reject a goal."""

_CANCELING = 3  # action_msgs/msg/GoalStatus.STATUS_CANCELING


def _as_action(fn: Callable[..., Any], name: str) -> Action[Any, Any, Any]:
    """``fn`` itself if it is an `Action`, else an action made of it, named after the server."""
    if isinstance(fn, Action):
        return fn
    if not inspect.iscoroutinefunction(fn):
        msg = (
            "a served function must be an 'async def' (or an @action) taking the robot "
            f"first, got {fn!r}"
        )
        raise TypeError(msg)
    served: Action[Any, Any, Any] = Action(fn)
    served.name = f"served {name}"
    return served


def refusal(response_type: type, reason: str) -> Any:
    """The response to a service request that was refused or whose action did not succeed.

    ``success`` False and ``reason`` in ``message`` where ``response_type``
    has a ``bool success`` (and a ``string message``), as std_srvs' Trigger
    and SetBool do; otherwise an empty response (ROS 2 has no other way to
    say no), which its client cannot tell from a real one.

    Examples:
        >>> from std_srvs.srv import SetBool  # doctest: +SKIP
        >>> refusal(SetBool.Response, "the e-stop is latched (cliff)")  # doctest: +SKIP
        std_srvs.srv.SetBool_Response(success=False, message='the e-stop is latched (cliff)')
    """
    response = response_type()
    fields = response_type.get_fields_and_field_types()  # type: ignore[attr-defined]
    if fields.get("success") == "boolean":
        response.success = False
        if fields.get("message") == "string":
            response.message = reason
    return response


def _start(
    robot: Robot, act: Action[Any, Any, Any], what: str, *args: Any
) -> ActionHandle[Any] | str:
    """Start the action, or say why it cannot run (``what``: goals or requests, for the fix)."""
    if robot.emergency_stopped:
        return (
            f"the emergency stop is latched ({robot.emergency_stop_reason}); "
            f"robot.clear_emergency_stop() lets {what} in again"
        )
    try:
        return act(robot, *args)
    except Ros2Error:
        raise
    except Exception as error:  # the executive refuses it (max_actions, shutting down): said
        return str(error)


def _answer(decision: concurrent.futures.Future[Any], answer: object) -> bool:
    """Answer the ROS thread; False if it stopped waiting (its request is refused)."""
    try:
        decision.set_result(answer)
    except concurrent.futures.InvalidStateError:
        return False
    return True


def _why_not(handle: ActionHandle[Any]) -> str | None:
    """After the action's first step: None if it runs (or succeeded), else why it could not."""
    if handle.done() and handle.outcome is not Outcome.SUCCEEDED:
        return str(handle.exception())
    return None


class _Server:
    """What both servers share: the robot, its ROS thread, the interface, the served action.

    Attributes:
        name: The action's or service's full name.
        interface: Its ROS 2 action or service type.
    """

    kind = "server"
    part = "Goal"  # what the interface's class has, as a generated action or service has
    example = "test_msgs.action.Fibonacci"
    asks = "goals"

    def __init__(
        self, robot: Robot, thread: RosThread, name: str, interface: type, fn: Callable[..., Any]
    ) -> None:
        if not hasattr(interface, self.part):
            msg = f"{interface!r} is not a ROS 2 {self.kind} type (such as {self.example})"
            raise TypeError(msg)
        self.robot, self.thread, self.name, self.interface = robot, thread, name, interface
        self.action = _as_action(fn, name)
        self.handles: set[ActionHandle[Any]] = set()
        robot.add_emergency_stop_callback(self._stopped)

    def _stopped(self, _reason: str) -> set[ActionHandle[Any]]:
        """The emergency stop ends every goal or request running, resources held or not."""
        return set(self.handles)

    def close(self) -> None:
        """Stop serving (the running goals' actions are the robot's, and end with it)."""
        self.robot.remove_emergency_stop_callback(self._stopped)

    def _begin(self, decision: concurrent.futures.Future[Any], *args: Any) -> None:
        """On the loop: start the action; answer ``decision`` after its first step."""
        if decision.cancelled():  # the ROS thread stopped waiting: refused already
            return
        started = _start(self.robot, self.action, self.asks, *args)
        if isinstance(started, str):
            _answer(decision, started)
            return
        self.handles.add(started)
        started.add_done_callback(self.handles.discard)
        self.thread.loop.call_soon(self._decide, started, decision)

    @staticmethod
    def _decide(handle: ActionHandle[Any], decision: concurrent.futures.Future[Any]) -> None:
        reason = _why_not(handle)
        if not _answer(decision, handle if reason is None else reason):
            handle.cancel("its ROS 2 request was refused: the answer came too late")

    def _ask_loop(self, *args: Any) -> ActionHandle[Any] | str:
        """On the ROS thread: start the action on the loop; its handle, or why it cannot run."""
        decision: concurrent.futures.Future[Any] = concurrent.futures.Future()
        self.thread.to_loop(self._begin, decision, *args)
        try:
            answer: ActionHandle[Any] | str = decision.result(timeout=DECISION_BOUND)
        except concurrent.futures.TimeoutError:
            # Refused, unless the answer came in between: the loop then sees it cancelled.
            late = not decision.cancel()
            answer = (
                decision.result()
                if late
                else f"the robot's event loop did not answer within {DECISION_BOUND:g} s"
            )
        if isinstance(answer, str):
            _log.warning("%s %s refused a request: %s", self.kind, self.name, answer)
        return answer

    def _report(self, handle: ActionHandle[Any]) -> str:
        """Log (a WARNING) how ``handle``'s action ended, which was not a success; say it."""
        ending = f"its action {handle.name}#{handle.id} ended {handle.outcome.name}: "
        ending += str(handle.exception())
        _log.warning("%s %s: %s", self.kind, self.name, ending)
        return ending


class Ros2ActionServer(_Server):
    """A ROS 2 action server whose goals run as pyrobots_aio actions (`Ros2Node.serve_action`)."""

    kind = "action server"

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        action_type = self.action_type = self.interface
        # Only the ROS thread (rclpy's callbacks) uses these. An accepted goal's action and
        # feedback sender, by id(goal) until rclpy makes its goal handle; then its action by
        # goal id until the goal is executed.
        self._accepted: dict[int, tuple[ActionHandle[Any], _FeedbackSender]] = {}
        self._goals: dict[bytes, ActionHandle[Any]] = {}
        self._server = rclpy_module("rclpy.action").ActionServer(
            self.thread.node,
            action_type,
            self.name,
            execute_callback=self._execute,
            goal_callback=self._on_goal,
            handle_accepted_callback=self._on_accepted,
            cancel_callback=self._on_cancel,
        )

    # -- on the ROS thread ---------------------------------------------------------

    def _on_goal(self, goal: Any) -> Any:
        responses = rclpy_module("rclpy.action").GoalResponse
        feedback = _FeedbackSender(self.action_type)
        answer = self._ask_loop(goal, feedback)
        if isinstance(answer, str):
            return responses.REJECT
        self._accepted[id(goal)] = (answer, feedback)
        return responses.ACCEPT

    def _on_accepted(self, goal_handle: Any) -> None:
        handle, feedback = self._accepted.pop(id(goal_handle.request))
        feedback.attach(goal_handle)
        self._goals[bytes(goal_handle.goal_id.uuid)] = handle
        self.thread.to_loop(handle.add_done_callback, lambda _: goal_handle.execute())

    def _on_cancel(self, goal_handle: Any) -> Any:
        handle = self._goals.get(bytes(goal_handle.goal_id.uuid))
        if handle is not None:
            self.thread.to_loop(handle.cancel, "cancelled by its ROS 2 client")
        return rclpy_module("rclpy.action").CancelResponse.ACCEPT

    def _execute(self, goal_handle: Any) -> Any:
        """The goal's action is done: its final status, and its result."""
        handle = self._goals.pop(bytes(goal_handle.goal_id.uuid))
        result = self._result(handle)
        if result is not None:
            goal_handle.succeed()
            return result
        if handle.outcome is Outcome.CANCELLED and goal_handle.status == _CANCELING:
            goal_handle.canceled()
        else:
            if handle.outcome is not Outcome.SUCCEEDED:  # (a wrong result is logged already)
                self._report(handle)
            goal_handle.abort()
        return self.action_type.Result()  # type: ignore[attr-defined]

    def _result(self, handle: ActionHandle[Any]) -> Any:
        """The goal's result if its action succeeded with one (None: an empty one)."""
        if handle.outcome is not Outcome.SUCCEEDED:
            return None
        value = handle.result()
        result_type = self.action_type.Result  # type: ignore[attr-defined]
        if value is None:
            return result_type()
        if isinstance(value, result_type):
            return value
        _log.error(
            "action server %s: its action returned %r, not a %s result; the goal is aborted",
            self.name,
            value,
            ros_name(self.action_type),
        )
        return None

    def close(self) -> None:
        """Stop serving (the goals' actions are the robot's, and end with it)."""
        super().close()
        self._server.destroy()

    def __repr__(self) -> str:
        return f"<Ros2ActionServer {self.name} {ros_name(self.action_type)} {self.action.name}>"


class _FeedbackSender:
    """The feedback callable a served action gets: ``feedback(message)`` or ``feedback(**fields)``.

    Feedback sent before rclpy made the goal's handle (in the action's first
    step) is kept, the latest only, and published once the handle is there.
    """

    def __init__(self, action_type: type) -> None:
        self.feedback_type: Any = action_type.Feedback  # type: ignore[attr-defined]
        self._lock = threading.Lock()  # the loop sends, the ROS thread attaches
        self._goal_handle: Any = None
        self._early: Any = None

    def attach(self, goal_handle: Any) -> None:
        """On the ROS thread: the goal's handle; the feedback kept until now goes out."""
        with self._lock:
            self._goal_handle, early, self._early = goal_handle, self._early, None
        if early is not None:
            goal_handle.publish_feedback(early)

    def __call__(self, message: Any = None, /, **fields: Any) -> None:
        if message is None:
            message = self.feedback_type(**fields)
        elif fields or not isinstance(message, self.feedback_type):
            msg = (
                f"feedback takes a {ros_name(self.feedback_type)} or its fields as keywords, "
                f"got {message!r} and {fields!r}"
            )
            raise TypeError(msg)
        with self._lock:
            goal_handle = self._goal_handle
            if goal_handle is None:
                self._early = message
                return
        if goal_handle.is_active:
            goal_handle.publish_feedback(message)


class Ros2ServiceServer(_Server):
    """A ROS 2 service whose requests run as pyrobots_aio actions (`Ros2Node.serve_service`)."""

    kind = "service"
    part = "Request"
    example = "std_srvs.srv.SetBool"
    asks = "requests"

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.srv_type = self.interface
        self._service = self.thread.node.create_service(self.srv_type, self.name, self._on_request)
        self._send = self._service.send_response
        # rclpy sends what the callback returns with the request's header, which the
        # callback never sees: a deferred reply learns the header here instead.
        self._service.send_response = self._on_send

    def _on_request(self, request: Any, _response: Any) -> Any:
        answer = self._ask_loop(request)
        if isinstance(answer, str):
            return refusal(self.srv_type.Response, answer)  # type: ignore[attr-defined]
        return _Reply(self, answer)

    def _on_send(self, response: Any, header: Any) -> None:
        if isinstance(response, _Reply):
            response.learn(header)
        else:
            self._send(response, header)

    def response(self, handle: ActionHandle[Any]) -> Any:
        """The response to send for ``handle``'s request (a `refusal` if it did not succeed)."""
        response_type = self.srv_type.Response  # type: ignore[attr-defined]
        if handle.outcome is Outcome.SUCCEEDED and isinstance(handle.result(), response_type):
            return handle.result()
        if handle.outcome is Outcome.SUCCEEDED and handle.result() is None:
            return response_type()  # an empty response, as asked
        if handle.outcome is Outcome.SUCCEEDED:
            reason = (
                f"its action returned {handle.result()!r}, not a {ros_name(self.srv_type)} response"
            )
            _log.error("service %s: %s", self.name, reason)
        else:
            reason = self._report(handle)
        return refusal(response_type, reason)

    def send(self, response: Any, header: Any) -> None:
        """Send ``response`` with the request's ``header`` (from any thread)."""
        self._send(response, header)

    def close(self) -> None:
        """Stop serving."""
        super().close()
        self.thread.node.destroy_service(self._service)

    def __repr__(self) -> str:
        return f"<Ros2ServiceServer {self.name} {ros_name(self.srv_type)} {self.action.name}>"


class _Reply:
    """A deferred service response: sent once both the header and the action's end are known."""

    def __init__(self, server: Ros2ServiceServer, handle: ActionHandle[Any]) -> None:
        self._server, self._lock = server, threading.Lock()
        self._header: Any = None
        self._response: Any = None
        server.thread.to_loop(handle.add_done_callback, self._done)

    def learn(self, header: Any) -> None:  # on the ROS thread
        with self._lock:
            self._header = header
            response = self._response
        if response is not None:
            self._server.send(response, header)

    def _done(self, handle: ActionHandle[Any]) -> None:  # on the loop
        response = self._server.response(handle)
        with self._lock:
            self._response = response
            header = self._header
        if header is not None:
            self._server.send(response, header)
