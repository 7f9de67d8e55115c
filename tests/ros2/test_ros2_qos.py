"""A QoS mismatch on a bridged topic is an error naming both profiles, not a silent topic.

rclpy reports an incompatible peer with an event (``incompatible_qos``);
the bridge names its own profile and the peer's (read from the graph), logs
it once, and every wait of the endpoint raises it.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, require_rclpy, wait_for

require_rclpy()

from geometry_msgs.msg import Twist  # noqa: E402
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks  # noqa: E402
from rclpy.qos import (  # noqa: E402
    DurabilityPolicy,
    QoSProfile,
    ReliabilityPolicy,
    qos_profile_sensor_data,
)

from pyrobots_aio import QosMismatchError  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

    from pyrobots_aio import Robot

pytestmark = pytest.mark.asyncio


def named_in(endpoints: list[Any], node: str) -> bool:
    """Whether the graph names ``node`` among ``endpoints`` (it learns names after QoS)."""
    return any(endpoint.node_name == node for endpoint in endpoints)


async def test_a_reliable_subscription_to_a_best_effort_publisher_names_both_profiles(
    executive: Robot, plain: Callable[..., PlainNode], caplog: pytest.LogCaptureFixture
) -> None:
    teleop = plain("best_effort_teleop")
    quiet = PublisherEventCallbacks(incompatible_qos=lambda _: None)  # (rclpy's own warns)
    teleop.node.create_publisher(Twist, "/qos_cmd", qos_profile_sensor_data, event_callbacks=quiet)
    async with executive, asyncio.timeout(DEADLINE):
        graph = executive.ros2.node.get_publishers_info_by_topic
        await wait_for(lambda: named_in(graph("/qos_cmd"), "best_effort_teleop"))
        sub = executive.ros2.subscribe("/qos_cmd", Twist, {"v": "linear.x"}, qos=7)
        with pytest.raises(QosMismatchError) as caught:
            await sub.wait_for_message()
        with pytest.raises(QosMismatchError):
            await sub.wait_for_publishers()
    expected = (
        "QoS mismatch on /qos_cmd: this subscription (reliable, volatile, keep last 7) and the "
        "publisher of /best_effort_teleop (best effort, volatile) are "
        "incompatible in RELIABILITY, so no message passes between them; a best-effort "
        "publisher needs a best-effort subscription (qos='sensor_data')"
    )
    assert str(caught.value) == expected
    assert sub.error is caught.value
    errors = [r.getMessage() for r in caplog.records if r.levelno == logging.ERROR]
    assert errors == [expected]


async def test_a_transient_local_subscription_to_a_volatile_publisher_names_both_profiles(
    executive: Robot, plain: Callable[..., PlainNode]
) -> None:
    latched = QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    listener = plain("latched_listener")
    quiet = SubscriptionEventCallbacks(incompatible_qos=lambda _: None)  # (rclpy's own warns)
    listener.node.create_subscription(
        Twist, "/qos_status", lambda _: None, latched, event_callbacks=quiet
    )
    async with executive, asyncio.timeout(DEADLINE):
        graph = executive.ros2.node.get_subscriptions_info_by_topic
        await wait_for(lambda: named_in(graph("/qos_status"), "latched_listener"))
        publisher = executive.ros2.publisher("/qos_status", Twist)
        with pytest.raises(QosMismatchError) as caught:
            await publisher.wait_for_subscribers()
    assert str(caught.value) == (
        "QoS mismatch on /qos_status: this publisher (reliable, volatile, keep last 10) and the "
        "subscription of /latched_listener (reliable, transient local) are "
        "incompatible in DURABILITY, so no message passes between them; a transient-local "
        "subscription needs a transient-local publisher"
    )
