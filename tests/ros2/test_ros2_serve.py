"""Actions and services served to ROS 2, driven by a plain rclpy client written here."""

from __future__ import annotations

import asyncio
import logging
import threading
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, PlainNode, require_rclpy, wait_for

require_rclpy()

from action_msgs.msg import GoalStatus  # noqa: E402
from rclpy.action import ActionClient, get_action_client_names_and_types_by_node  # noqa: E402
from rclpy.impl.implementation_singleton import rclpy_implementation  # noqa: E402
from std_srvs.srv import Empty, SetBool  # noqa: E402
from test_msgs.action import Fibonacci  # noqa: E402

from pyrobots_aio import (  # noqa: E402
    ActionCancelled,
    ActionHandle,
    ActionState,
    Resource,
    Robot,
    action,
    lock,
)
from pyrobots_aio.ros2 import attach_ros2  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Iterator

ARM = Resource("arm")


class Client:
    """A plain rclpy action client of ``/count`` and service client of ``/grip``, for the module.

    One client serves the whole module (see test_ros2_calls' FibonacciServer: re-creating
    both ends in one process, test after test, loses requests now and then).
    """

    def __init__(self) -> None:
        self.first_loop = asyncio.new_event_loop()  # each test hands it its own (`meet`)
        self.node = PlainNode("plain_client", loop=self.first_loop)
        self.actions = ActionClient(self.node.node, Fibonacci, "/count")
        self.services = {
            name: self.node.node.create_client(kind, name)
            for name, kind in [("/grip", SetBool), ("/reset", Empty)]
        }
        self.service = self.services["/grip"]

    def future(self, rclpy_future: Any) -> asyncio.Future[Any]:
        future: asyncio.Future[Any] = self.node.loop.create_future()
        rclpy_future.add_done_callback(
            lambda done: self.node.to_loop(future.set_result, done.result())
        )
        return future

    async def meet(self, robot: Robot, name: str = "/count") -> None:
        """Wait until each end of ``name`` sees the other (a server answers only a client it
        matched)."""
        self.node.loop = asyncio.get_running_loop()
        action = name == "/count"
        ready = self.actions.server_is_ready if action else self.services[name].service_is_ready
        await wait_for(ready)
        await wait_for(lambda: self._known(robot, name, action=action))

    def _known(self, robot: Robot, name: str, *, action: bool) -> bool:
        node = robot.ros2.node
        try:
            if action:
                clients = get_action_client_names_and_types_by_node(node, "plain_client", "/")
            else:
                clients = node.get_client_names_and_types_by_node("plain_client", "/")
        except (rclpy_implementation.NodeNameNonExistentError, rclpy_implementation.RCLError):
            return False  # not discovered yet
        return name in dict(clients)

    async def send(self, order: int, feedback: list[list[int]] | None = None) -> Any:
        def on_feedback(message: Any) -> None:
            if feedback is not None:
                self.node.to_loop(feedback.append, list(message.feedback.sequence))

        return await self.future(
            self.actions.send_goal_async(Fibonacci.Goal(order=order), on_feedback)
        )

    async def result(self, goal_handle: Any) -> Any:
        return await self.future(goal_handle.get_result_async())


@pytest.fixture(scope="module")
def client() -> Iterator[Client]:
    made = Client()
    yield made
    made.node.close()
    made.first_loop.close()


async def count(robot: Robot, goal: Any, feedback: Any) -> Fibonacci.Result:
    """Counts to ``goal.order``, a feedback per step, a step per second (order 0: forever)."""
    sequence: list[int] = []
    while goal.order == 0 or len(sequence) < goal.order:
        sequence.append(len(sequence))
        feedback(sequence=sequence)
        await robot.sleep(1.0 if goal.order else 0.05)
    return Fibonacci.Result(sequence=sequence)


def warnings_of(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [
        r.getMessage()
        for r in caplog.records
        if r.name == "pyrobots_aio.ros2" and r.levelno >= logging.WARNING
    ]


def served(robot: Robot) -> Robot:
    attach_ros2(robot, "executive")
    return robot


@pytest.mark.asyncio
async def test_a_goal_runs_as_an_action_with_feedback_and_its_result(client: Client) -> None:
    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        server = robot.ros2.serve_action("/count", Fibonacci, count)
        assert repr(server) == "<Ros2ActionServer /count test_msgs/action/Fibonacci served /count>"
        await client.meet(robot)
        feedback: list[list[int]] = []
        goal = await client.send(3, feedback)
        assert goal.accepted
        response = await client.result(goal)
        assert response.status == GoalStatus.STATUS_SUCCEEDED
        assert list(response.result.sequence) == [0, 1, 2]
        await wait_for(lambda: len(feedback) == 3)  # feedback may come after the result
        assert feedback == [[0], [0, 1], [0, 1, 2]]


@pytest.mark.asyncio
async def test_a_ros2_cancel_arrives_as_action_cancelled_and_the_goal_ends_canceled(
    client: Client,
) -> None:
    cleaned: list[str] = []

    @action
    async def forever(robot: Robot, goal: Any, feedback: Any) -> None:
        try:
            await count(robot, goal, feedback)
        except ActionCancelled:
            await robot.sleep(0.1)  # cleanup may await
            cleaned.append(robot.running()[0].cancel_reason or "")
            raise

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, forever)
        await client.meet(robot)
        feedback: list[list[int]] = []
        goal = await client.send(0, feedback)
        await wait_for(lambda: len(feedback) > 1)  # it runs
        answer = await client.future(goal.cancel_goal_async())
        assert len(answer.goals_canceling) == 1
        response = await client.result(goal)
        assert response.status == GoalStatus.STATUS_CANCELED
        assert cleaned == ["cancelled by its ROS 2 client"]


@pytest.mark.asyncio
async def test_a_goal_whose_resource_is_busy_is_rejected_with_the_reason(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    @action
    @lock(ARM)
    async def hold(robot: Robot) -> None:
        await robot.sleep(600)

    @action
    @lock(ARM, wait=False)
    async def wave(robot: Robot, goal: Any, feedback: Any) -> Fibonacci.Result:
        return await count(robot, goal, feedback)

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, wave)
        await client.meet(robot)
        holder = hold(robot)
        await robot.sleep(0)
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            goal = await client.send(1)
        assert not goal.accepted
        assert warnings_of(caplog) == [
            "action server /count refused a request: skipped: resource 'arm' is busy "
            f"(held by hold#{holder.id})"
        ]
        holder.cancel()
        await holder.wait_done()
        goal = await client.send(1)
        assert goal.accepted
        assert list((await client.result(goal)).result.sequence) == [0]


@pytest.mark.asyncio
async def test_a_goal_is_rejected_while_the_emergency_stop_is_latched(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, count)
        await client.meet(robot)
        await robot.emergency_stop("operator")
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            goal = await client.send(1)
        assert not goal.accepted
        assert warnings_of(caplog) == [
            "action server /count refused a request: the emergency stop is latched (operator); "
            "robot.clear_emergency_stop() lets goals in again"
        ]


@pytest.mark.asyncio
async def test_a_goal_preempted_by_a_higher_priority_ends_aborted(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    @action
    @lock(ARM, priority=0)
    async def wave(robot: Robot, goal: Any, feedback: Any) -> Fibonacci.Result:
        return await count(robot, goal, feedback)

    @action
    @lock(ARM, priority=5, preempt=True)
    async def reflex(robot: Robot) -> str:
        return "safe"

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, wave)
        await client.meet(robot)
        feedback: list[list[int]] = []
        goal = await client.send(0, feedback)
        await wait_for(lambda: len(feedback) > 1)
        (holder,) = robot.running()
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            assert await reflex(robot) == "safe"
            response = await client.result(goal)
        assert response.status == GoalStatus.STATUS_ABORTED
        assert warnings_of(caplog) == [
            f"action server /count: its action wave#{holder.id} ended CANCELLED: action "
            f"wave#{holder.id} was cancelled by reflex#{holder.id + 1}: preempted by "
            f"reflex#{holder.id + 1} (priority 5) for 'arm'"
        ]


@pytest.mark.asyncio
async def test_a_served_request_runs_as_an_action_and_its_return_is_the_response(
    client: Client,
) -> None:
    @action
    @lock(ARM)
    async def grip(robot: Robot, request: Any) -> SetBool.Response:
        await robot.sleep(0.2)
        return SetBool.Response(success=request.data, message="closed")

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_service("/grip", SetBool, grip)
        await client.meet(robot, "/grip")
        response = await client.future(client.service.call_async(SetBool.Request(data=True)))
        assert (response.success, response.message) == (True, "closed")


class Refusals(logging.Handler):
    """Sets ``refused`` (a thread's event) when a server logs that it refused a request."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.refused = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        if "refused a request" in record.getMessage():
            self.refused.set()


@pytest.mark.asyncio
async def test_a_goal_the_loop_does_not_decide_in_time_is_rejected_and_never_runs(
    client: Client, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    from pyrobots_aio.ros2 import _serve

    monkeypatch.setattr(_serve, "DECISION_BOUND", 0.2)
    started: list[int] = []

    async def never(robot: Robot, goal: Any, feedback: Any) -> None:
        started.append(goal.order)

    refusals = Refusals()
    logging.getLogger("pyrobots_aio.ros2").addHandler(refusals)
    try:
        async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
            robot.ros2.serve_action("/count", Fibonacci, never)
            await client.meet(robot)
            with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
                sent = client.future(client.actions.send_goal_async(Fibonacci.Goal(order=1)))
                # The loop is stuck (on purpose) until the server gave up waiting for it.
                assert refusals.refused.wait(DEADLINE)
                goal = await sent
                assert not goal.accepted
                assert warnings_of(caplog) == [
                    "action server /count refused a request: the robot's event loop did not "
                    "answer within 0.2 s"
                ]
            assert started == []  # the start came to the loop after the refusal: nothing ran
    finally:
        logging.getLogger("pyrobots_aio.ros2").removeHandler(refusals)


async def assert_paused(
    robot: Robot, handle: ActionHandle[Any], feedback: list[list[int]], result: asyncio.Future[Any]
) -> None:
    """``handle``'s goal, just paused, is frozen: no feedback, and still active for its client."""
    sent = len(feedback)
    await robot.sleep(0)  # frozen at its next resumption point
    assert handle.state is ActionState.PAUSED
    await robot.sleep(1.5)  # longer than a step: a running count would send feedback
    assert len(feedback) == sent
    assert not result.done()


@pytest.mark.asyncio
async def test_a_paused_goal_stays_active_without_feedback_and_resumed_it_succeeds(
    client: Client,
) -> None:
    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, count)
        await client.meet(robot)
        feedback: list[list[int]] = []
        goal = await client.send(3, feedback)
        result = asyncio.ensure_future(client.result(goal))
        await wait_for(lambda: len(feedback) == 1)
        (handle,) = robot.handles()
        handle.pause("operator")
        await assert_paused(robot, handle, feedback, result)
        handle.resume()
        await wait_for(lambda: len(feedback) == 2)
        robot.pause_all()
        await assert_paused(robot, handle, feedback, result)
        robot.resume_all()
        response = await result
        assert response.status == GoalStatus.STATUS_SUCCEEDED
        assert list(response.result.sequence) == [0, 1, 2]  # the pauses unwound nothing
        await wait_for(lambda: len(feedback) == 3)
        assert feedback == [[0], [0, 1], [0, 1, 2]]


@pytest.mark.asyncio
async def test_an_emergency_stop_ends_a_running_goal_aborted_even_without_resources(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, count)  # it holds no resource
        await client.meet(robot)
        feedback: list[list[int]] = []
        goal = await client.send(0, feedback)
        await wait_for(lambda: len(feedback) > 1)  # it runs
        (handle,) = robot.handles()
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            stop = robot.emergency_stop("operator")
            response = await client.result(goal)
        assert response.status == GoalStatus.STATUS_ABORTED
        assert list(response.result.sequence) == []  # an empty result
        await stop
        assert warnings_of(caplog) == [
            f"action server /count: its action served /count#{handle.id} ended CANCELLED: "
            f"action served /count#{handle.id} was cancelled by emergency_stop#{stop.id}: "
            "emergency stop: operator"
        ]


@pytest.mark.asyncio
async def test_a_refused_request_is_answered_success_false_with_the_reason(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    @action
    async def grip(robot: Robot, request: Any) -> SetBool.Response:
        await robot.sleep(0.05 if not request.data else 600)
        if not request.data:  # past its first step: the request was taken
            msg = "the gripper is jammed"
            raise RuntimeError(msg)
        return SetBool.Response(success=True, message="closed")

    async def call(data: bool) -> Any:
        return await client.future(client.service.call_async(SetBool.Request(data=data)))

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_service("/grip", SetBool, grip)
        await client.meet(robot, "/grip")
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            failed = await call(False)  # its action fails
            running = asyncio.ensure_future(call(True))
            await robot.wait(lambda r: bool(r.handles()), poll=0.01)
            (handle,) = robot.handles()
            stop = robot.emergency_stop("operator")  # ends the request running
            stopped = await running
            refused = await call(True)  # and refuses the next
            await stop
    ended = f"its action grip#{handle.id} ended"
    assert [(r.success, r.message) for r in (failed, stopped, refused)] == [
        (False, f"its action grip#{handle.id - 1} ended FAILED: the gripper is jammed"),
        (
            False,
            f"{ended} CANCELLED: action grip#{handle.id} was cancelled by "
            f"emergency_stop#{stop.id}: emergency stop: operator",
        ),
        (
            False,
            "the emergency stop is latched (operator); robot.clear_emergency_stop() lets "
            "requests in again",
        ),
    ]
    assert warnings_of(caplog) == [
        f"service /grip: {failed.message}",
        f"service /grip: {stopped.message}",
        f"service /grip refused a request: {refused.message}",
    ]


@pytest.mark.asyncio
async def test_a_refused_request_of_a_type_with_no_success_field_is_answered_empty(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    async def never(robot: Robot, request: Any) -> None:
        raise AssertionError  # never runs: the stop is latched

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_service("/reset", Empty, never)
        await client.meet(robot, "/reset")
        await robot.emergency_stop("operator")
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            call = client.services["/reset"].call_async(Empty.Request())
            response = await client.future(call)
    assert response == Empty.Response()  # all ROS 2 allows: its client cannot tell
    assert warnings_of(caplog) == [
        "service /reset refused a request: the emergency stop is latched (operator); "
        "robot.clear_emergency_stop() lets requests in again"
    ]


@pytest.mark.asyncio
async def test_a_goal_whose_action_returns_no_result_ends_aborted_said_once(
    client: Client, caplog: pytest.LogCaptureFixture
) -> None:
    async def wrong(robot: Robot, goal: Any, feedback: Any) -> str:
        return "done"

    async with served(Robot()) as robot, asyncio.timeout(DEADLINE):
        robot.ros2.serve_action("/count", Fibonacci, wrong)
        await client.meet(robot)
        with caplog.at_level(logging.WARNING, "pyrobots_aio.ros2"):
            response = await client.result(await client.send(1))
    assert response.status == GoalStatus.STATUS_ABORTED
    assert warnings_of(caplog) == [
        "action server /count: its action returned 'done', not a test_msgs/action/Fibonacci "
        "result; the goal is aborted"
    ]
