"""Topics into the state and out of publishers, against plain rclpy nodes written here.

The tests marked ``feed`` run twice: with the subscription rung on the loop by
DDS itself (where this system allows it) and with the receiver thread's feed.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import threading
import time
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, next_where, require_rclpy

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data  # noqa: E402
from sensor_msgs.msg import Range  # noqa: E402

from pyrobots_aio import Robot  # noqa: E402
from pyrobots_aio.ros2 import attach_ros2  # noqa: E402
from pyrobots_aio.ros2._doorbell import doorbells_available  # noqa: E402
from pyrobots_aio.ros2._rclpy import qos_profile  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode


@pytest.fixture(params=["loop", "thread"])
def feed(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """How the subscriptions' messages reach the loop: rung by DDS, or a receiver thread."""
    if request.param == "thread":
        monkeypatch.setattr("pyrobots_aio.ros2._receiver.doorbells_available", lambda: False)
    elif not doorbells_available():
        pytest.skip("no eventfd doorbell on this system (Linux on x86-64 or AArch64 has one)")
    return str(request.param)


def twist(v: float, w: float) -> Any:
    message = Twist()
    message.linear.x, message.angular.z = v, w
    return message


@pytest.mark.asyncio
async def test_a_plain_twist_publisher_feeds_the_state_and_a_monitor(
    plain: Callable[..., PlainNode], feed: str
) -> None:
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive")
    fired = asyncio.Event()
    async with robot, asyncio.timeout(DEADLINE):
        sub = robot.ros2.subscribe("/teleop", Twist, {"v": "linear.x", "w": "angular.z"})
        publisher, matched = teleop.publisher("/teleop", Twist)
        await matched.wait()
        publisher.publish(twist(0.0, 0.0))
        first = await sub.wait_for_message()
        assert (first.linear.x, robot.state.v, robot.state.w) == (0.0, 0.0, 0.0)
        robot.whenever("v", above=0.1).do(fired.set)
        publisher.publish(twist(0.3, -0.2))
        await fired.wait()
        assert (robot.state.v, robot.state.w) == (0.3, -0.2)
        assert sub.received == 2
        assert sub.topic == "/teleop"
        assert sub.keys == {"v", "w"}
        assert sub.publishers == 1  # the matched count: rung, or waited on by the receiver
        receivers = [t for t in threading.enumerate() if t.name.endswith(" receiver")]
        assert len(receivers) == (feed == "thread")  # rung: no thread between DDS and the loop


@pytest.mark.asyncio
async def test_to_state_as_a_function_and_as_a_key(plain: Callable[..., PlainNode]) -> None:
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive", namespace="/robot1")
    async with robot, asyncio.timeout(DEADLINE):
        speed = robot.ros2.subscribe(
            "cmd_vel", Twist, lambda m: {"speed": math.hypot(m.linear.x, 0.4)}
        )
        whole = robot.ros2.subscribe("cmd_vel", Twist, "last_cmd")
        publisher, matched = teleop.publisher("/robot1/cmd_vel", Twist, subscribers=2)
        await matched.wait()
        both = asyncio.gather(speed.wait_for_message(), whole.wait_for_message())
        publisher.publish(twist(0.3, 1.0))
        _, message = await both
        assert whole.topic == "/robot1/cmd_vel"
        assert robot.state.last_cmd is message
        assert message.angular.z == 1.0
        assert robot.state.speed == pytest.approx(0.5)


@pytest.mark.asyncio
@pytest.mark.usefixtures("feed")
async def test_a_callback_runs_on_the_loop_with_each_message(
    plain: Callable[..., PlainNode],
) -> None:
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive")
    seen: list[float] = []
    loop = asyncio.get_running_loop()
    async with robot, asyncio.timeout(DEADLINE):

        def on_twist(message: Any) -> None:
            assert asyncio.get_running_loop() is loop
            seen.append(message.linear.x)

        sub = robot.ros2.subscribe("/teleop", Twist, callback=on_twist)
        publisher, matched = teleop.publisher("/teleop", Twist)
        await matched.wait()
        for v in (0.1, 0.2, 0.3):
            publisher.publish(twist(v, 0.0))
        while len(seen) < 3:
            await sub.wait_for_message()
        assert seen == [0.1, 0.2, 0.3]  # reliable and in order
        assert "v" not in robot.state


@pytest.mark.asyncio
async def test_a_publisher_reaches_a_plain_odometry_listener(
    plain: Callable[..., PlainNode],
) -> None:
    listener = plain("odom_listener")
    inbox = listener.inbox("/robot1/odom", Odometry)
    robot = Robot()
    attach_ros2(robot, "base", namespace="/robot1")
    async with robot, asyncio.timeout(DEADLINE):
        odom = robot.ros2.publisher("odom", Odometry)
        assert odom.topic == "/robot1/odom"
        assert await odom.wait_for_subscribers() == 1
        message = Odometry()
        message.header.frame_id = "odom"
        message.pose.pose.position.x = 1.5
        odom.publish(message)
        received = await inbox.get()
        assert (received.header.frame_id, received.pose.pose.position.x) == ("odom", 1.5)
        assert odom.subscribers == 1


@pytest.mark.asyncio
@pytest.mark.usefixtures("feed")
async def test_sensor_data_is_best_effort_both_ways(plain: Callable[..., PlainNode]) -> None:
    sensor = plain("ir_driver")
    listener = plain("ir_listener")
    inbox = listener.inbox("/ir_front", Range, qos_profile_sensor_data)
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        sub = robot.ros2.subscribe("/ir_front", Range, {"ir_front": "range"}, qos="sensor_data")
        mine = robot.ros2.publisher("/ir_front", Range, qos="sensor_data")
        publisher, matched = sensor.publisher(
            "/ir_front", Range, qos_profile_sensor_data, subscribers=2
        )
        await matched.wait()
        await mine.wait_for_subscribers(2)  # the plain listener and the robot's subscription
        ray = Range(range=0.25)
        while "ir_front" not in robot.state:  # best effort: the first ones may be lost
            publisher.publish(ray)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(sub.wait_for_message(), 0.5)
        assert robot.state.ir_front == pytest.approx(0.25)
        received = None
        while received is None:
            mine.publish(Range(range=0.5))
            with contextlib.suppress(TimeoutError):
                received = await asyncio.wait_for(next_where(inbox, lambda m: m.range > 0.4), 0.5)
        assert received.range == 0.5


@pytest.mark.asyncio
@pytest.mark.usefixtures("feed")
async def test_a_lagging_loop_drops_the_oldest_messages_as_keep_last_does(
    plain: Callable[..., PlainNode],
) -> None:
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        sub = robot.ros2.subscribe("/teleop", Twist, {"v": "linear.x"}, qos=5)
        publisher, matched = teleop.publisher("/teleop", Twist, 50)
        await matched.wait()
        # Block the loop (on purpose) while DDS hands over 20 messages, one at a time.
        deadline = time.monotonic() + DEADLINE
        for v in range(20):
            publisher.publish(twist(float(v), 0.0))
            while sub.queued + sub.dropped <= v and time.monotonic() < deadline:
                time.sleep(0.001)  # noqa: ASYNC251 - blocking the loop is the point
        assert (sub.queued, sub.dropped) == (5, 15)
        oldest_kept = await sub.wait_for_message()  # the drain delivers the five in order
        assert (oldest_kept.linear.x, sub.received, robot.state.v) == (15.0, 5, 19.0)
        assert robot.state.version("v") == 5


@pytest.mark.asyncio
@pytest.mark.usefixtures("feed")
async def test_topics_reach_the_state_while_rclpys_executor_is_busy(
    plain: Callable[..., PlainNode],
) -> None:
    # The bridge's subscriptions are taken by the node's receiver, not by rclpy's
    # executor: a slow rclpy callback of the node's (a user's raw timer) does not hold them.
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive")
    loop = asyncio.get_running_loop()
    busy: asyncio.Future[None] = loop.create_future()
    release = threading.Event()

    def slow() -> None:  # on the executor's thread, which it holds until released
        loop.call_soon_threadsafe(lambda: busy.done() or busy.set_result(None))
        release.wait(DEADLINE)

    async with robot, asyncio.timeout(DEADLINE):
        sub = robot.ros2.subscribe("/teleop", Twist, {"v": "linear.x"})
        timer = robot.ros2.node.create_timer(0.001, slow)
        try:
            await busy
            publisher, matched = teleop.publisher("/teleop", Twist)
            await matched.wait()
            await sub.wait_for_publishers()
            publisher.publish(twist(0.4, 0.0))
            await sub.wait_for_message()
            assert (robot.state.v, sub.publishers) == (0.4, 1)
        finally:
            timer.cancel()
            release.set()


@pytest.mark.asyncio
@pytest.mark.usefixtures("feed")
async def test_subscriptions_closed_under_a_flood_leave_the_receiver_quiet(
    plain: Callable[..., PlainNode], caplog: pytest.LogCaptureFixture
) -> None:
    # A subscription closed while the receiver was taking from it (or running its
    # matched handler) made the receiver fail: destruction was requested meanwhile.
    teleop = plain("teleop")
    publisher, _ = teleop.publisher("/flood", Twist, 100)
    teleop.node.create_timer(0.0005, lambda: publisher.publish(twist(0.1, 0.0)))
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        for _ in range(30):
            sub = robot.ros2.subscribe("/flood", Twist, {"v": "linear.x"}, qos=100)
            await sub.wait_for_message()
            sub.close()
    assert [r.getMessage() for r in caplog.records if r.levelname == "ERROR"] == []


@pytest.mark.asyncio
async def test_two_robots_in_one_process_each_have_their_own_node(
    plain: Callable[..., PlainNode],
) -> None:
    teleop = plain("teleop")
    first, second = Robot(), Robot()
    attach_ros2(first, "first")
    attach_ros2(second, "second")
    async with first, second, asyncio.timeout(DEADLINE):
        assert first.ros2.node.context is not second.ros2.node.context
        subs = [r.ros2.subscribe("/teleop", Twist, {"v": "linear.x"}) for r in (first, second)]
        publisher, matched = teleop.publisher("/teleop", Twist, subscribers=2)
        await matched.wait()
        waits = [asyncio.ensure_future(s.wait_for_message()) for s in subs]
        publisher.publish(twist(0.7, 0.0))
        await asyncio.gather(*waits)
        assert (first.state.v, second.state.v) == (0.7, 0.7)


def test_qos_profiles_are_rclpys_presets_depths_or_profiles() -> None:
    sensor = qos_profile("sensor_data")
    assert sensor.reliability == ReliabilityPolicy.BEST_EFFORT
    assert qos_profile("default").reliability == ReliabilityPolicy.RELIABLE
    assert qos_profile(3).depth == 3
    own = QoSProfile(depth=7)
    assert qos_profile(own) is own
    with pytest.raises(
        ValueError, match=r"^unknown QoS profile 'fast'; known profiles: \['default'"
    ):
        qos_profile("fast")
    with pytest.raises(ValueError, match=r"^a QoS history depth must be at least 1, got 0$"):
        qos_profile(0)
    with pytest.raises(TypeError, match="qos must be a history depth, a profile name or an rclpy"):
        qos_profile(1.5)
