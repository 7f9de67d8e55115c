"""How messages reach the loop: rung by DDS itself where it can, else by the receiver thread.

test_ros2_topics runs its delivery tests both ways; here: the doorbells' own
file descriptors, and the fallback when the RMW refuses them.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import os
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, require_rclpy, wait_for

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from rclpy.event_handler import PublisherEventCallbacks  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402

from pyrobots_aio import QosMismatchError, Robot  # noqa: E402
from pyrobots_aio.ros2 import _doorbell, attach_ros2  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

needs_doorbells = pytest.mark.skipif(
    not _doorbell.doorbells_available(),
    reason="no eventfd doorbell on this system (Linux on x86-64 or AArch64 has one)",
)


def _twist(v: float) -> Any:
    message = Twist()
    message.linear.x = v
    return message


def _receivers() -> list[str]:
    return [t.name for t in threading.enumerate() if t.name.endswith(" receiver")]


def _eventfds() -> int:
    """The eventfds this process holds open."""
    fds = Path("/proc/self/fd")
    return sum(1 for fd in fds.iterdir() if "eventfd" in _link(fd))


def _link(fd: Path) -> str:
    try:
        return os.readlink(fd)
    except OSError:  # closed since it was listed
        return ""


@needs_doorbells
@pytest.mark.asyncio
async def test_closing_a_subscription_closes_its_doorbells() -> None:
    gc.collect()  # what earlier tests left for the collector closes now, not during the count
    before = _eventfds()
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot:
        running = _eventfds()  # the node's own (rcl's guard conditions, the watchdog's)
        sub = robot.ros2.subscribe("/teleop", Twist, {"v": "linear.x"})
        assert _eventfds() == running + 3  # its messages, its matched count, its QoS mismatch
        sub.close()
        assert _eventfds() == running
    assert _eventfds() == before


@needs_doorbells
@pytest.mark.asyncio
async def test_an_rmw_refusing_listener_callbacks_falls_back_to_the_receiver_thread(
    plain: Callable[..., PlainNode],
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    real = _doorbell._rcl()
    assert isinstance(real, _doorbell._Rcl)
    refused = _doorbell._Rcl(
        on_message=lambda *_: 3,  # RCL_RET_UNSUPPORTED, as an RMW without them answers
        on_event=real.on_event,  # its events were hung first: they are unhung
        reset_error=real.reset_error,
        ring=real.ring,
    )
    monkeypatch.setattr(_doorbell, "_rcl", lambda: refused)
    caplog.set_level(logging.INFO, "pyrobots_aio.ros2")
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        running = _eventfds()
        sub = robot.ros2.subscribe("/teleop", Twist, {"v": "linear.x"})
        assert _eventfds() == running  # every bell closed again
        publisher, matched = teleop.publisher("/teleop", Twist)
        await matched.wait()
        assert await sub.wait_for_publishers() == 1
        publisher.publish(_twist(0.3))
        await sub.wait_for_message()
        assert robot.state.v == 0.3
        assert len(_receivers()) == 1
        robot.ros2.subscribe("/other", Twist, {"w": "angular.z"})  # not tried again
    assert [r.getMessage() for r in caplog.records if "through a thread" in r.getMessage()] == [
        "ROS 2 messages reach the loop through a thread: the RMW refuses listener callbacks "
        "(rcl returned 3)"
    ]


@pytest.mark.asyncio
async def test_a_qos_mismatch_reaches_a_subscription_fed_by_the_receiver_thread(
    plain: Callable[..., PlainNode], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("pyrobots_aio.ros2._receiver.doorbells_available", lambda: False)
    teleop = plain("best_effort_teleop")
    quiet = PublisherEventCallbacks(incompatible_qos=lambda _: None)  # (rclpy's own warns)
    teleop.node.create_publisher(Twist, "/qos_cmd", qos_profile_sensor_data, event_callbacks=quiet)
    robot = Robot()
    attach_ros2(robot, "executive")
    async with robot, asyncio.timeout(DEADLINE):
        graph = robot.ros2.node.get_publishers_info_by_topic
        await wait_for(lambda: any(p.node_name == "best_effort_teleop" for p in graph("/qos_cmd")))
        sub = robot.ros2.subscribe("/qos_cmd", Twist, {"v": "linear.x"}, qos=7)
        with pytest.raises(QosMismatchError) as caught:
            await sub.wait_for_publishers()
        assert len(_receivers()) == 1
    assert str(caught.value).startswith(
        "QoS mismatch on /qos_cmd: this subscription (reliable, volatile, keep last 7) and the "
        "publisher of /best_effort_teleop (best effort, volatile) are incompatible in RELIABILITY"
    )
