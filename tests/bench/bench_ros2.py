"""Benchmarks of the ROS 2 bridge (DESIGN.md §10), each beside plain rclpy in the same run.

Real DDS (Fast DDS) between real processes on this machine, discovery kept
on localhost in a domain of its own. Latencies are one-way and per message:
the sender puts ``time.perf_counter_ns()`` (CLOCK_MONOTONIC, shared by every
process here) in each message and the receiver's time is compared with that
message's own stamp.

- ``topic_to_callback_*``: a message from a sender process until a monitor
  callback runs on ``robot.state`` in a bridge process, beside a plain rclpy
  subscription callback in a process of its own (a message lost on the way
  is not counted: ``*_samples_*`` says how many came). The sender sends on both
  sides' topics at 250 Hz each, half a period apart, alternating which
  goes first; each side has its process (and its GIL) to itself;
- ``publish_to_wire_*``: ``node.publisher(...).publish`` (what
  ``drive()`` will use) until the message reaches another process, beside a
  plain rclpy publisher in the same process, alternately;
- ``drive_to_wire_*``: `Ros2Robot.drive` (checks, the e-stop latch, a
  ``Twist`` built and published on ``cmd_vel``) until the ``Twist`` reaches
  another process, beside a plain rclpy ``Twist`` built and published in the
  same process, alternately (each command's speed tells it apart; the other
  process feeds the robot the odometry it needs to run);
- ``flood_*``, ``*_zero_loss_*``: the highest rate each side absorbs with
  zero loss (every message of a ``FLOOD_SECONDS`` burst counted into the
  state, or by a plain rclpy callback), sent at a paced rate by a process
  of its own; the rate doubles until a burst loses one, then is bisected;
  the two sides' bursts alternate. Both subscriptions keep ``FLOOD_DEPTH``
  messages, so a burst longer than that queue shows the receiver's own
  sustained rate.

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

KINDS = ("bridge", "plain")
LATENCY_N = 1_500
PERIOD = 0.004  # seconds between two latency messages on one topic: 250 Hz, a fast sensor
FLOOD_SECONDS = 2.0  # each burst: long enough that the queues cannot hide a slow receiver
FLOOD_DEPTH = 1_000  # history depth of both sides' subscriptions (and of the sender)
FLOOD_START = 2_000.0  # messages/s of the first burst
FLOOD_ROUNDS = 8  # bursts per side at most
FLOOD_RESOLUTION = 1.1  # the search stops once the lossy rate is within 10 % of the lossless


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


# -- the helper processes ------------------------------------------------------------


def _wait_matched(publisher: Any, wanted: int = 1) -> None:
    """Block until ``publisher`` matches ``wanted`` subscriptions, matched from their side too."""
    while publisher.get_subscription_count() < wanted:
        time.sleep(0.01)
    time.sleep(0.5)


def _send_latency() -> None:
    """Latency messages on both latency topics, half a period apart, each stamped when sent."""
    from std_msgs.msg import Int64

    plain = _Plain("bench_send")
    publishers = {
        kind: plain.node.create_publisher(Int64, f"/bench/latency_{kind}", 100) for kind in KINDS
    }
    print("ready", flush=True)
    sys.stdin.readline()
    for publisher in publishers.values():
        _wait_matched(publisher)
    order = list(KINDS)
    for _ in range(LATENCY_N):
        order.reverse()  # neither side always first
        for kind in order:
            publishers[kind].publish(Int64(data=time.perf_counter_ns()))
            time.sleep(PERIOD / 2)
    print("done", flush=True)
    plain.close()


def _plain_latency() -> None:
    """A plain rclpy subscription callback: its latency from each message's own stamp."""
    from std_msgs.msg import Int64

    plain = _Plain("bench_plain_latency")
    samples: list[int] = []
    plain.node.create_subscription(
        Int64,
        "/bench/latency_plain",
        lambda m: samples.append(time.perf_counter_ns() - m.data),
        100,
    )
    print("ready", flush=True)
    sys.stdin.readline()
    print(json.dumps(samples), flush=True)
    plain.close()


def _bridge_latency() -> None:
    """The bridge: topic -> ``robot.state`` -> a monitor callback, which notes its time.

    A monitor callback is not given the value that fired it, so it notes only
    when it ran; its n-th run answers the n-th message delivered (every
    message fires the monitor, in order), whose stamp the subscription's own
    callback noted as it was delivered. Both lists go back to the parent.
    """
    asyncio.run(_bridge_latency_main())


async def _bridge_latency_main() -> None:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    robot = Robot()
    node = attach_ros2(robot, "bench_bridge_latency")
    stamps: list[int] = []
    ran: list[int] = []
    async with robot:
        node.subscribe(
            "/bench/latency_bridge",
            Int64,
            {"stamp": "data"},
            callback=lambda m: stamps.append(m.data),
            qos=100,
        )
        robot.state.stamp = 0
        monitor = robot.whenever("stamp", increase=1, max_firing_freq=0, blocking=False)
        monitor.do(lambda: ran.append(time.perf_counter_ns()))
        print("ready", flush=True)
        await asyncio.to_thread(sys.stdin.readline)
        print(json.dumps({"stamps": stamps, "ran": ran}), flush=True)


def _send_flood() -> None:
    """Bursts at a given rate: ``KIND RATE`` on stdin; answers the rate achieved."""
    from std_msgs.msg import Int64

    plain = _Plain("bench_flood")
    publishers = {
        kind: plain.node.create_publisher(Int64, f"/bench/flood_{kind}", FLOOD_DEPTH)
        for kind in KINDS
    }
    print("ready", flush=True)
    for publisher in publishers.values():
        _wait_matched(publisher)
    while line := sys.stdin.readline():
        kind, rate = line.split()
        print(json.dumps(_burst(publishers[kind], float(rate))), flush=True)
    plain.close()


def _burst(publisher: Any, rate: float) -> dict[str, float]:
    """Send ``rate`` messages/s for ``FLOOD_SECONDS``, paced to the millisecond."""
    from std_msgs.msg import Int64

    count = round(rate * FLOOD_SECONDS)
    period = 1.0 / rate
    start = time.perf_counter()
    for n in range(count):
        ahead = start + n * period - time.perf_counter()
        if ahead > 0.001:
            time.sleep(ahead)
        publisher.publish(Int64(data=n))
    took = time.perf_counter() - start
    return {"sent": count, "rate": (count - 1) / took if took else rate}


def _plain_flood() -> None:
    """A plain rclpy subscription counting a flood; ``N`` on stdin: how many came of N."""
    from std_msgs.msg import Int64

    plain = _Plain("bench_plain_flood")
    got = [0]

    def on_message(_message: Any) -> None:
        got[0] += 1

    plain.node.create_subscription(Int64, "/bench/flood_plain", on_message, FLOOD_DEPTH)
    print("ready", flush=True)
    while line := sys.stdin.readline():
        print(_settled(got, int(line)), flush=True)
        got[0] = 0
    plain.close()


def _bridge_flood() -> None:
    """The bridge counting a flood into ``robot.state``; ``N`` on stdin: how many came of N."""
    asyncio.run(_bridge_flood_main())


async def _bridge_flood_main() -> None:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    robot = Robot()
    node = attach_ros2(robot, "bench_bridge_flood")
    got = [0]

    def on_flood(_changes: object) -> None:
        got[0] += 1

    async with robot:
        node.subscribe("/bench/flood_bridge", Int64, lambda m: {"flood": m.data}, qos=FLOOD_DEPTH)
        robot.state.subscribe(on_flood, keys="flood")
        print("ready", flush=True)
        while line := await asyncio.to_thread(sys.stdin.readline):
            print(await asyncio.to_thread(_settled, got, int(line)), flush=True)
            got[0] = 0


def _settled(got: list[int], wanted: int) -> int:
    """``got[0]`` once it reaches ``wanted`` or stops growing for half a second."""
    last, still = -1, 0.0
    while got[0] < wanted and still < 0.5:  # a count in another thread: looked at, not awaited
        still = still + 0.05 if got[0] == last else 0.0
        last = got[0]
        time.sleep(0.05)
    return got[0]


def _receive_wire() -> None:
    """What ``publish_to_wire`` sends, from both sides: each message's latency."""
    from std_msgs.msg import Int64

    plain = _Plain("bench_receive")
    got: dict[str, list[int]] = {"bridge": [], "plain": []}
    for kind in got:
        plain.node.create_subscription(
            Int64,
            f"/bench/wire_{kind}",
            lambda m, k=kind: got[k].append(time.perf_counter_ns() - m.data),
            1000,
        )
    print("ready", flush=True)
    sys.stdin.readline()
    print(json.dumps(got), flush=True)
    plain.close()


def _receive_twists() -> None:
    """What ``drive_to_wire`` sends: each command's first arrival; odometry for the robot."""
    from geometry_msgs.msg import Twist

    plain = _Plain("bench_twists")
    # The first arrival of each command (the bridge re-sends one with each odometry).
    first: dict[str, dict[float, int]] = {"bridge": {}, "plain": {}}

    def arrived(kind: str) -> Callable[[Any], None]:
        def on_twist(message: Any) -> None:
            first[kind].setdefault(message.linear.x, time.perf_counter_ns())

        return on_twist

    for kind in first:
        plain.node.create_subscription(Twist, f"/bench/{kind}/cmd_vel", arrived(kind), 1000)
    _feed_odometry(plain.node)
    print("ready", flush=True)
    sys.stdin.readline()
    print(json.dumps({k: {v: t for v, t in f.items() if v} for k, f in first.items()}), flush=True)
    plain.close()


HELPERS: dict[str, Callable[[], None]] = {
    "send_latency": _send_latency,
    "plain_latency": _plain_latency,
    "bridge_latency": _bridge_latency,
    "send_flood": _send_flood,
    "plain_flood": _plain_flood,
    "bridge_flood": _bridge_flood,
    "receive_wire": _receive_wire,
    "receive_twists": _receive_twists,
}


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


def _topic_to_callback() -> dict[str, float]:
    receivers = {kind: _start(f"{kind}_latency") for kind in KINDS}
    sender = _start("send_latency")
    try:
        assert _tell(sender, "go").strip() == "done"
        time.sleep(0.5)  # the last messages on their way
        got = {kind: json.loads(_tell(receiver, "")) for kind, receiver in receivers.items()}
    finally:
        for process in (sender, *receivers.values()):
            process.wait()
    stamps, ran = got["bridge"]["stamps"], got["bridge"]["ran"]
    if len(ran) != len(stamps):
        msg = (
            f"the bridge's monitor ran {len(ran)} times for {len(stamps)} messages delivered: "
            "its runs are paired with the messages in order, so none may be missing"
        )
        raise RuntimeError(msg)
    bridge = [end - stamp for end, stamp in zip(ran, stamps, strict=True)]
    plain = got["plain"]
    return {
        **_stats("topic_to_callback_bridge", bridge),
        **_stats("topic_to_callback_plain_rclpy", plain),
        "topic_to_callback_samples_bridge": float(len(bridge)),
        "topic_to_callback_samples_plain_rclpy": float(len(plain)),
        "topic_to_callback_sent_each": float(LATENCY_N),
        "ros2_topic_to_callback_median_ratio": statistics.median(bridge) / statistics.median(plain),
        "ros2_topic_to_callback_p99_ratio": _p99(bridge) / _p99(plain),
    }


# -- publish -> on the wire ----------------------------------------------------------------


async def _publish_to_wire() -> dict[str, float]:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    receiver = _start("receive_wire")
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

    receiver = _start("receive_twists")
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


class _Search:
    """The highest rate with zero loss: doubled from ``FLOOD_START`` until a loss, then bisected."""

    def __init__(self) -> None:
        self.lossless = 0.0  # the highest rate achieved without loss
        self.lossy = float("inf")  # the lowest rate achieved with a loss
        self.publisher_limited = False

    @property
    def done(self) -> bool:
        return self.lossy <= self.lossless * FLOOD_RESOLUTION

    def next_rate(self) -> float:
        if self.lossy == float("inf"):
            return 2 * self.lossless if self.lossless else FLOOD_START
        return (self.lossless * self.lossy) ** 0.5 if self.lossless else self.lossy / 2

    def record(self, wanted: float, achieved: float, lost: int) -> None:
        if lost:
            self.lossy = min(self.lossy, achieved)
            return
        self.lossless = max(self.lossless, achieved)
        if achieved < 0.9 * wanted:  # the sender's own limit: no higher rate to try
            self.publisher_limited = True
            self.lossy = self.lossless


def _flood() -> dict[str, float]:
    receivers = {kind: _start(f"{kind}_flood") for kind in KINDS}
    sender = _start("send_flood")
    searches = {kind: _Search() for kind in KINDS}
    trials = dict.fromkeys(KINDS, 0.0)
    order = list(KINDS)
    try:
        for _ in range(FLOOD_ROUNDS):
            order.reverse()  # neither side always first
            for kind in order:
                search = searches[kind]
                if search.done:
                    continue
                wanted = search.next_rate()
                burst = json.loads(_tell(sender, f"{kind} {wanted}"))
                got = int(_tell(receivers[kind], str(burst["sent"])))
                search.record(wanted, burst["rate"], max(0, burst["sent"] - got))
                trials[kind] += 1
    finally:
        for process in (sender, *receivers.values()):
            assert process.stdin is not None
            process.stdin.close()
            process.wait()
    bridge, plain = searches["bridge"], searches["plain"]
    return {
        "flood_seconds_per_trial": FLOOD_SECONDS,
        "flood_trials_bridge": trials["bridge"],
        "flood_trials_plain_rclpy": trials["plain"],
        "flood_lossy_bridge_msgs_per_s": bridge.lossy if bridge.lossy < float("inf") else 0.0,
        "flood_lossy_plain_rclpy_msgs_per_s": plain.lossy if plain.lossy < float("inf") else 0.0,
        "flood_publisher_limited": float(bridge.publisher_limited or plain.publisher_limited),
        "ros2_bridge_zero_loss_msgs_per_s": bridge.lossless,
        "ros2_plain_rclpy_zero_loss_msgs_per_s": plain.lossless,
        "ros2_zero_loss_rate_ratio": bridge.lossless / plain.lossless if plain.lossless else 0.0,
    }


def run() -> dict[str, float]:
    if importlib.util.find_spec("rclpy") is None:
        print("  skipped: rclpy is not installed (pip install 'pyrobots-aio[ros2]')")
        return {}
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(102, 200)))
    results = _topic_to_callback()
    for bench in (_publish_to_wire, _drive_to_wire):
        results.update(asyncio.run(bench()))
    results.update(_flood())
    return results


if __name__ == "__main__":
    HELPERS[sys.argv[1]]()
