"""Benchmarks of the ROS 2 bridge (DESIGN.md §10), each beside plain rclpy in the same run.

Real DDS (Fast DDS) between real processes on this machine, discovery kept
on localhost in a domain of its own. Latencies are one-way: the sender puts
``time.perf_counter_ns()`` (CLOCK_MONOTONIC, shared by every process here)
in an ``std_msgs/Int64`` and the receiver subtracts it from its own clock.

- ``topic_to_callback_*``: a message from another process, until a monitor
  callback runs on ``robot.state`` (the bridge), beside a plain rclpy
  subscription callback in the same process, on the same messages;
- ``publish_to_wire_*``: ``node.publisher(...).publish`` (what
  ``drive()`` will use) until the message reaches another process, beside a
  plain rclpy publisher in the same process, alternately;
- ``drive_to_wire_*``: `Ros2Robot.drive` (checks, the e-stop latch, a
  ``Twist`` built and published on ``cmd_vel``) until the ``Twist`` reaches
  another process, beside a plain rclpy ``Twist`` built and published in the
  same process, alternately (each command's speed tells it apart; the other
  process feeds the robot the odometry it needs to run);
- ``flood_*``: a burst from another process as fast as it can send, counted
  into the state by the bridge and by a plain rclpy callback beside it.

Without rclpy the module prints why and returns nothing.
"""

from __future__ import annotations

import asyncio
import importlib.util
import json
import os
import random
import statistics
import subprocess
import sys
import threading
import time
from typing import TYPE_CHECKING, Any

from .bench_events import _p99, _stats

if TYPE_CHECKING:
    from collections.abc import Callable

LATENCY_N = 1_500
PERIOD = 0.004  # seconds between two latency messages: 250 Hz, a fast sensor
FLOOD_N = 20_000


class _Plain:
    """A plain rclpy node on its own context and thread: the baseline."""

    def __init__(self, name: str) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.context = Context()
        self.context.init(args=[])
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, name=f"plain {name}")
        self.thread.start()

    def close(self) -> None:
        self.executor.shutdown()
        self.thread.join()
        self.node.destroy_node()
        self.context.try_shutdown()


# -- the helper process ---------------------------------------------------------------


def _helper(mode: str) -> None:
    """The other process: ``send`` latency messages or a ``flood``, or ``receive`` them."""
    from std_msgs.msg import Int64

    plain = _Plain(f"bench_{mode}")
    node = plain.node
    if mode == "twists":
        from geometry_msgs.msg import Twist

        # The first arrival of each command (the bridge re-sends one with each odometry).
        first: dict[str, dict[float, int]] = {"bridge": {}, "plain": {}}

        def arrived(kind: str) -> Callable[[Any], None]:
            def on_twist(message: Any) -> None:
                first[kind].setdefault(message.linear.x, time.perf_counter_ns())

            return on_twist

        for kind in first:
            node.create_subscription(Twist, f"/bench/{kind}/cmd_vel", arrived(kind), 1000)
        _feed_odometry(node)
        print("ready", flush=True)
        sys.stdin.readline()
        print(
            json.dumps({k: {v: t for v, t in f.items() if v} for k, f in first.items()}), flush=True
        )
    elif mode == "receive":
        got: dict[str, list[int]] = {"bridge": [], "plain": []}
        for kind in got:
            node.create_subscription(
                Int64,
                f"/bench/wire_{kind}",
                lambda m, k=kind: got[k].append(time.perf_counter_ns() - m.data),
                1000,
            )
        print("ready", flush=True)
        sys.stdin.readline()
        print(json.dumps(got), flush=True)
    else:
        topic = "/bench/latency" if mode == "send" else "/bench/flood"
        publisher = node.create_publisher(Int64, topic, 1000)
        print("ready", flush=True)
        wanted = int(sys.stdin.readline())
        while publisher.get_subscription_count() < wanted:
            time.sleep(0.01)
        time.sleep(0.5)  # both subscriptions matched from their side too
        count = LATENCY_N if mode == "send" else FLOOD_N
        for _ in range(count):
            publisher.publish(Int64(data=time.perf_counter_ns()))
            if mode == "send":
                time.sleep(PERIOD)
        print("done", flush=True)
        sys.stdin.readline()
    plain.close()


def _feed_odometry(node: object) -> None:
    """Publish what a `Ros2Robot` on ``/bench`` waits for (odometry, flags) at 50 Hz."""
    from nav_msgs.msg import Odometry
    from std_msgs.msg import Bool

    odom = node.create_publisher(Odometry, "/bench/bridge/odom", 10)  # type: ignore[attr-defined]
    flags = [
        node.create_publisher(Bool, f"/bench/bridge/{key}", 10)  # type: ignore[attr-defined]
        for key in ("bumper", "bumper_left", "bumper_right", "docked")
    ]

    def publish() -> None:
        odom.publish(Odometry())
        for flag in flags:
            flag.publish(Bool())

    node.create_timer(0.02, publish)  # type: ignore[attr-defined]


def _start(mode: str) -> subprocess.Popen[str]:
    process = subprocess.Popen(
        [sys.executable, "-m", "tests.bench.bench_ros2", mode],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "ready"
    return process


def _tell(process: subprocess.Popen[str], line: str) -> str:
    assert process.stdin is not None
    assert process.stdout is not None
    process.stdin.write(line + "\n")
    process.stdin.flush()
    return process.stdout.readline()


# -- topic -> state -> monitor callback --------------------------------------------------


async def _topic_to_callback() -> dict[str, float]:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    bridge: list[float] = []
    plain_samples: list[float] = []
    plain = _Plain("bench_plain_sub")
    plain.node.create_subscription(
        Int64,
        "/bench/latency",
        lambda m: plain_samples.append(time.perf_counter_ns() - m.data),
        100,
    )
    sender = _start("send")
    robot = Robot()
    node = attach_ros2(robot, "bench_bridge")
    try:
        async with robot:
            sub = node.subscribe("/bench/latency", Int64, {"stamp": "data"}, qos=100)
            robot.state.stamp = 0

            def on_stamp() -> None:
                bridge.append(time.perf_counter_ns() - robot.state.stamp)

            robot.whenever("stamp", increase=1, blocking=False).do(on_stamp)
            assert (await asyncio.to_thread(_tell, sender, "2")).strip() == "done"
            async with asyncio.timeout(60):
                while sub.received < LATENCY_N - sub.dropped:
                    await sub.wait_for_message()
            await asyncio.sleep(0.1)
    finally:
        _tell(sender, "")
        sender.wait()
        plain.close()
    return {
        **_stats("topic_to_callback_bridge", bridge),
        **_stats("topic_to_callback_plain_rclpy", plain_samples),
        "topic_to_callback_samples": float(len(bridge)),
        "ros2_topic_to_callback_p99_ratio": _p99(bridge) / _p99(plain_samples),
    }


# -- publish -> on the wire ----------------------------------------------------------------


async def _publish_to_wire() -> dict[str, float]:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    receiver = _start("receive")
    plain = _Plain("bench_plain_pub")
    plain_pub = plain.node.create_publisher(Int64, "/bench/wire_plain", 1000)
    robot = Robot()
    node = attach_ros2(robot, "bench_bridge")
    calls: dict[str, list[float]] = {"bridge": [], "plain": []}
    try:
        async with robot:
            bridge_pub = node.publisher("/bench/wire_bridge", Int64, qos=1000)
            await bridge_pub.wait_for_subscribers()
            while plain_pub.get_subscription_count() < 1:  # noqa: ASYNC110 - a graph fact
                await asyncio.sleep(0.01)
            await asyncio.sleep(0.5)  # matched from the receiver's side too
            pairs = [("bridge", bridge_pub.publish), ("plain", plain_pub.publish)]
            for n in range(LATENCY_N):
                for kind, publish in pairs if n % 2 else pairs[::-1]:
                    start = time.perf_counter_ns()
                    publish(Int64(data=start))
                    calls[kind].append(time.perf_counter_ns() - start)
                await asyncio.sleep(PERIOD)
            await asyncio.sleep(0.5)
            got = json.loads(_tell(receiver, ""))
    finally:
        receiver.wait()
        plain.close()
    return {
        **_stats("publish_to_wire_bridge", got["bridge"]),
        **_stats("publish_to_wire_plain_rclpy", got["plain"]),
        "publish_call_bridge_median_us": statistics.median(calls["bridge"]) / 1e3,
        "publish_call_plain_rclpy_median_us": statistics.median(calls["plain"]) / 1e3,
        "ros2_publish_to_wire_p99_ratio": _p99(got["bridge"]) / _p99(got["plain"]),
    }


# -- drive() -> cmd_vel on the wire ---------------------------------------------------------


async def _drive_to_wire() -> dict[str, float]:
    from geometry_msgs.msg import Twist

    from pyrobots_aio.motion import SENSORS
    from pyrobots_aio.ros2 import Ros2Robot

    receiver = _start("twists")
    plain = _Plain("bench_plain_twist")
    plain_pub = plain.node.create_publisher(Twist, "/bench/plain/cmd_vel", 1000)
    flags = [s for s in SENSORS if s.key in ("bumper", "bumper_left", "bumper_right", "docked")]
    robot = Ros2Robot(namespace="/bench/bridge", sensors=flags)
    sent: dict[str, dict[int, int]] = {"bridge": {}, "plain": {}}

    def plain_drive(v: float) -> None:
        twist = Twist()
        twist.linear.x = v
        plain_pub.publish(twist)

    try:
        async with robot:
            await robot.cmd_vel.wait_for_subscribers()
            while plain_pub.get_subscription_count() < 1:  # noqa: ASYNC110 - a graph fact
                await asyncio.sleep(0.01)
            await asyncio.sleep(0.5)  # matched from the receiver's side too

            def bridge_drive(v: float) -> None:
                robot.drive(v, 0.0)

            drives = [("bridge", bridge_drive), ("plain", plain_drive)]
            for n in range(1, LATENCY_N + 1):  # each command's speed, n, tells it apart
                for kind, drive in drives if n % 2 else drives[::-1]:
                    sent[kind][n] = time.perf_counter_ns()
                    drive(float(n))
                await asyncio.sleep(PERIOD)
            robot.stop()
            await asyncio.sleep(0.5)
            got = json.loads(_tell(receiver, ""))
    finally:
        receiver.wait()
        plain.close()
    latency = {
        kind: [arrived - sent[kind][int(float(v))] for v, arrived in got[kind].items()]
        for kind in sent
    }
    return {
        **_stats("drive_to_wire_bridge", latency["bridge"]),
        **_stats("drive_to_wire_plain_rclpy", latency["plain"]),
        "ros2_drive_to_wire_p99_ratio": _p99(latency["bridge"]) / _p99(latency["plain"]),
    }


# -- flood ------------------------------------------------------------------------------------


async def _flood() -> dict[str, float]:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    plain_times: list[int] = []
    plain = _Plain("bench_plain_flood")
    plain.node.create_subscription(
        Int64, "/bench/flood", lambda m: plain_times.append(time.perf_counter_ns()), 1000
    )
    bridge_times: list[int] = []
    lag: list[int] = []
    flooder = _start("flood")
    robot = Robot()
    node = attach_ros2(robot, "bench_bridge")
    try:
        async with robot:
            sub = node.subscribe("/bench/flood", Int64, lambda m: {"flood": m.data}, qos=1000)

            def on_flood(_changes: object) -> None:
                bridge_times.append(time.perf_counter_ns())
                lag.append(sub.queued)

            robot.state.subscribe(on_flood, keys="flood")
            assert (await asyncio.to_thread(_tell, flooder, "2")).strip() == "done"
            for _ in range(200):  # what is still on its way
                count = sub.received
                await asyncio.sleep(0.05)
                if sub.received == count and len(plain_times) >= len(bridge_times):
                    break
            dropped = sub.dropped
    finally:
        _tell(flooder, "")
        flooder.wait()
        plain.close()

    def rate(times: list[int]) -> float:
        return (len(times) - 1) / ((times[-1] - times[0]) / 1e9) if len(times) > 1 else 0.0

    return {
        "flood_sent": float(FLOOD_N),
        "flood_bridge_received": float(len(bridge_times)),
        "flood_plain_rclpy_received": float(len(plain_times)),
        "flood_bridge_dropped_by_lag": float(dropped),
        "flood_bridge_max_queued": float(max(lag, default=0)),
        "ros2_bridge_msgs_per_s": rate(bridge_times),
        "ros2_plain_rclpy_msgs_per_s": rate(plain_times),
    }


def run() -> dict[str, float]:
    if importlib.util.find_spec("rclpy") is None:
        print("  skipped: rclpy is not installed (pip install 'pyrobots-aio[ros2]')")
        return {}
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(102, 200)))
    results: dict[str, float] = {}
    for bench in (_topic_to_callback, _publish_to_wire, _drive_to_wire, _flood):
        results.update(asyncio.run(bench()))
    return results


if __name__ == "__main__":
    _helper(sys.argv[1])
