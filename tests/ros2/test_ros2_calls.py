"""Service calls and action goals against plain rclpy servers written here."""

from __future__ import annotations

import asyncio
import logging
import threading
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, PlainNode, meet, require_rclpy, wait_for

require_rclpy()

from rclpy.action import ActionServer, CancelResponse, GoalResponse  # noqa: E402
from rclpy.callback_groups import ReentrantCallbackGroup  # noqa: E402
from std_srvs.srv import SetBool, Trigger  # noqa: E402
from test_msgs.action import Fibonacci  # noqa: E402

from pyrobots_aio import (  # noqa: E402
    ActionHandle,
    ActionInterrupted,
    GoalError,
    GoalRejectedError,
    Outcome,
    Robot,
)
from pyrobots_aio.ros2 import attach_ros2  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator


def gripper(request: Any, response: Any) -> Any:
    response.success = request.data
    response.message = "closed" if request.data else "open"
    return response


@pytest.mark.asyncio
async def test_a_call_reaches_a_plain_service_and_returns_its_response(
    plain: Callable[..., PlainNode],
) -> None:
    server = plain("gripper_driver")
    server.node.create_service(SetBool, "/robot1/gripper", gripper)
    robot = Robot()
    attach_ros2(robot, "executive", namespace="/robot1")
    async with robot, asyncio.timeout(DEADLINE):
        await meet(robot, server, "/robot1/gripper", SetBool)
        response = await robot.ros2.call("gripper", SetBool.Request(data=True))
        assert (response.success, response.message) == (True, "closed")
        response = await robot.ros2.call("/robot1/gripper", SetBool.Request(data=False))
        assert (response.success, response.message) == (False, "open")


@pytest.mark.asyncio
async def test_a_call_waits_for_its_server_to_appear(plain: Callable[..., PlainNode]) -> None:
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        call = asyncio.ensure_future(robot.ros2.call("/late", Trigger.Request()))
        await asyncio.sleep(0)
        assert not call.done()
        server = plain("late_driver", spin=False)  # it answers once it knows the client
        server.node.create_service(
            Trigger, "/late", lambda _req, resp: Trigger.Response(success=True, message="here")
        )
        name = robot.ros2.name
        await wait_for(lambda: server.knows_client(name, "/", "/late", action=False))
        server.spin()
        assert (await call).message == "here"


@pytest.mark.asyncio
async def test_a_cancelled_call_drops_its_request_and_the_client_still_works(
    plain: Callable[..., PlainNode],
) -> None:
    server = plain("slow_driver")
    entered, release = asyncio.Event(), threading.Event()

    def slow(_request: Any, response: Any) -> Any:
        server.to_loop(entered.set)
        release.wait(DEADLINE)  # the plain server holds its only thread until released
        response.success = True
        return response

    server.node.create_service(Trigger, "/slow", slow)
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        await meet(robot, server, "/slow", Trigger)
        call = asyncio.ensure_future(robot.ros2.call("/slow", Trigger.Request()))
        await entered.wait()
        call.cancel()
        with pytest.raises(asyncio.CancelledError):
            await call
        entered.clear()
        release.set()  # the first response now arrives, for a request nobody waits for
        response = await robot.ros2.call("/slow", Trigger.Request())
        assert response.success


class FibonacciServer:
    """A plain rclpy action server: rejects orders over 40, aborts 13, holds 0 until released.

    One server serves the whole module, as a robot's servers outlive its
    clients. (Destroying and re-creating both a server and a client in one
    process, test after test, loses goal requests now and then: a Fast DDS
    artifact of participants re-created in one process, not seen across
    processes, where a first request is at worst delayed by one heartbeat.)
    """

    def __init__(self, node: PlainNode) -> None:
        self.node = node
        self.reset()
        ActionServer(
            node.node,
            Fibonacci,
            "/fibonacci",
            execute_callback=self.execute,
            goal_callback=lambda goal: (
                GoalResponse.REJECT if goal.order > 40 else GoalResponse.ACCEPT
            ),
            cancel_callback=self.cancel,
            callback_group=ReentrantCallbackGroup(),
        )

    def reset(self, *, refuse_cancel: bool = False) -> FibonacciServer:
        self.ended: list[str] = []
        self.release = threading.Event()
        self.refuse_cancel = refuse_cancel
        return self

    def cancel(self, _goal_handle: Any) -> Any:
        return CancelResponse.REJECT if self.refuse_cancel else CancelResponse.ACCEPT

    def execute(self, goal_handle: Any) -> Any:
        order, sequence = goal_handle.request.order, [0, 1]
        for _ in range(1, order):
            sequence.append(sequence[-1] + sequence[-2])
            goal_handle.publish_feedback(Fibonacci.Feedback(sequence=sequence))
        if order == 13:
            goal_handle.abort()
            self.ended.append("aborted")
            return Fibonacci.Result(sequence=sequence)
        if order == 0:  # feedback every 20 ms (the first may be lost) until released or cancelled
            while not goal_handle.is_cancel_requested and not self.release.wait(0.02):
                goal_handle.publish_feedback(Fibonacci.Feedback(sequence=[-1]))
            if goal_handle.is_cancel_requested:
                goal_handle.canceled()
                self.ended.append("canceled")
                return Fibonacci.Result(sequence=[])
            sequence = [42]
        goal_handle.succeed()
        self.ended.append("succeeded")
        return Fibonacci.Result(sequence=sequence)


async def held_goal(robot: Robot, server: FibonacciServer) -> ActionHandle[Any]:
    """A goal the server executes until released or cancelled, once its feedback is in."""
    await meet(robot, server.node, "/fibonacci", Fibonacci)
    handle = robot.ros2.goal(
        "/fibonacci", Fibonacci.Goal(order=0), feedback_to_state={"fib": "sequence"}
    )
    await robot.wait(lambda r: "fib" in r.state)  # the server is executing it
    return handle


@pytest.fixture(scope="module")
def fibonacci_server() -> Iterator[FibonacciServer]:
    node = PlainNode("fibonacci_server", threads=4, loop=asyncio.new_event_loop())
    yield FibonacciServer(node)
    node.close()
    node.loop.close()


@pytest.fixture
def server(fibonacci_server: FibonacciServer) -> Iterator[FibonacciServer]:
    yield fibonacci_server.reset()
    fibonacci_server.release.set()  # a goal still held ends


@pytest.mark.asyncio
async def test_a_goal_is_an_action_whose_result_is_the_goals(
    server: FibonacciServer, executive: Robot
) -> None:
    async with executive as robot, asyncio.timeout(DEADLINE):
        await meet(robot, server.node, "/fibonacci", Fibonacci)
        handle = robot.ros2.goal("/fibonacci", Fibonacci.Goal(order=10))
        assert handle.name == "goal /fibonacci"
        result = await handle
        assert list(result.sequence) == [0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55]
        assert handle.outcome is Outcome.SUCCEEDED
        assert server.ended == ["succeeded"]


@pytest.mark.asyncio
async def test_feedback_lands_in_the_state_while_the_goal_runs(
    server: FibonacciServer, executive: Robot
) -> None:
    async with executive as robot, asyncio.timeout(DEADLINE):
        handle = await held_goal(robot, server)
        assert list(robot.state.fib) == [-1]
        assert not handle.done()
        server.release.set()
        assert list((await handle).sequence) == [42]


@pytest.mark.asyncio
async def test_cancelling_the_action_cancels_the_goal_and_waits_for_the_server(
    server: FibonacciServer, executive: Robot
) -> None:
    async with executive as robot, asyncio.timeout(DEADLINE):
        handle = await held_goal(robot, server)
        assert handle.cancel("bumped")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert server.ended == ["canceled"]  # the server's answer came before the action ended
        with pytest.raises(ActionInterrupted, match="was cancelled: bumped"):
            await handle


@pytest.mark.asyncio
async def test_a_goal_still_running_at_shutdown_is_cancelled_on_the_server(
    server: FibonacciServer, executive: Robot
) -> None:
    async with asyncio.timeout(DEADLINE):
        async with executive as robot:
            handle = await held_goal(robot, server)
        assert handle.outcome is Outcome.CANCELLED
        assert server.ended == ["canceled"]


@pytest.mark.asyncio
async def test_a_refused_cancel_is_logged_and_the_action_still_ends_cancelled(
    server: FibonacciServer, executive: Robot, caplog: pytest.LogCaptureFixture
) -> None:
    server.reset(refuse_cancel=True)
    async with executive as robot, asyncio.timeout(DEADLINE):
        handle = await held_goal(robot, server)
        handle.cancel()
        assert await handle.wait_done() is Outcome.CANCELLED
        server.release.set()  # the server's goal went on; let it finish
    warnings = [  # (the loop watchdog may report a stall of a loaded machine: not this test's)
        r.getMessage()
        for r in caplog.records
        if r.levelno == logging.WARNING and r.name == "pyrobots_aio.ros2"
    ]
    assert warnings == [
        "the action server of /fibonacci did not accept to cancel the goal "
        "(cancel response code 0, no goal canceling); it may go on"
    ]


@pytest.mark.asyncio
async def test_a_rejected_goal_fails_clearly(server: FibonacciServer, executive: Robot) -> None:
    async with executive as robot, asyncio.timeout(DEADLINE):
        await meet(robot, server.node, "/fibonacci", Fibonacci)
        handle = robot.ros2.goal("/fibonacci", Fibonacci.Goal(order=99))
        with pytest.raises(GoalRejectedError) as caught:
            await handle
        assert str(caught.value) == (
            "the action server of '/fibonacci' rejected the goal "
            "test_msgs.action.Fibonacci_Goal(order=99)"
        )
        assert (caught.value.action, caught.value.status) == ("/fibonacci", "rejected")
        assert handle.outcome is Outcome.FAILED


@pytest.mark.asyncio
async def test_an_aborted_goal_fails_with_its_status(
    server: FibonacciServer, executive: Robot
) -> None:
    async with executive as robot, asyncio.timeout(DEADLINE):
        await meet(robot, server.node, "/fibonacci", Fibonacci)
        with pytest.raises(GoalError) as caught:
            await robot.ros2.goal("/fibonacci", Fibonacci.Goal(order=13))
        assert caught.value.status == "aborted"
        assert str(caught.value).startswith("the goal on '/fibonacci' ended aborted by its server")
