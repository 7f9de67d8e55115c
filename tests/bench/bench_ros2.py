"""Benchmarks of the ROS 2 bridge (DESIGN.md §10), each beside plain rclpy in the same run.

Real DDS (Fast DDS) between real processes on this machine, discovery kept
on localhost in a domain of its own. Latencies are one-way and per message:
the sender puts ``time.perf_counter_ns()`` (CLOCK_MONOTONIC, shared by every
process here) in each message and the receiver's time is compared with that
message's own stamp.

Every comparison runs in rounds, the two sides interleaved within each round;
a ratio is the median of the rounds' ratios, printed with the lowest and
highest round (``*_lo``, ``*_hi``), so one unlucky round on a busy machine
neither makes nor breaks a goal.

- ``topic_to_callback_*``: a message from a sender process until a monitor
  callback runs on ``robot.state`` in a bridge process, beside a plain rclpy
  subscription callback in a process of its own (a message lost on the way
  is not counted: ``*_samples_*`` says how many came). The sender sends on both
  sides' topics at 250 Hz each, half a period apart, alternating which
  goes first; each side has its process (and its GIL) to itself. Each of
  ``LATENCY_ROUNDS`` rounds starts the three processes afresh, and counts
  as ``LATENCY_SLICES`` rounds of its consecutive messages: a process held
  up for a while on a busy machine spoils the p99 of one slice, not more;
- ``receive_cpu_*``: the CPU time (user and system, every thread) each of
  those receiving processes spent per message, its idle rate taken off:
  a cost the machine's load hardly changes, unlike the wall clock;
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
  a burst that loses is sent again before its rate counts as lossy. The two
  sides' bursts alternate, and each of ``FLOOD_ROUNDS`` rounds searches
  both sides afresh. Both subscriptions keep ``FLOOD_DEPTH`` messages, so a
  burst longer than that queue shows the receiver's own sustained rate. A
  rate the sender itself cannot reach ends a search there
  (``flood_publisher_limited``): that side absorbs at least that much. A
  message the sender's reliable publisher refuses (its history full of
  messages the receiver has not acknowledged) counts as lost.

Without rclpy the module prints why and returns nothing.
"""

from __future__ import annotations

import asyncio
import importlib.util
import json
import os
import random
import resource
import statistics
import subprocess
import sys
import threading
import time
from typing import TYPE_CHECKING, Any

from .bench_events import _p99, _stats

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

KINDS = ("bridge", "plain")
LATENCY_ROUNDS = 5  # rounds of the topic -> callback comparison, each in fresh processes
LATENCY_N = 2_000  # messages per side and round
LATENCY_SLICES = 2  # each round's ratios taken over this many consecutive slices of it
WIRE_N = 2_000  # messages per side of publish -> wire, and commands of drive -> wire
WIRE_ROUNDS = 5  # rounds (consecutive slices of the WIRE_N) of those two
PERIOD = 0.004  # seconds between two latency messages on one topic: 250 Hz, a fast sensor
IDLE_SECONDS = 1.0  # a receiver's idle CPU rate, measured before each round
FLOOD_ROUNDS = 3  # searches of each side's zero-loss rate
FLOOD_SECONDS = 2.0  # each burst: long enough that the queues cannot hide a slow receiver
FLOOD_DEPTH = 1_000  # history depth of both sides' subscriptions (and of the sender)
FLOOD_START = 2_000.0  # messages/s of the first burst
FLOOD_BURSTS = 8  # rates tried per side and search at most
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


def _cpu_seconds() -> float:
    """CPU time of this process so far, every thread, user and system."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


class _CpuMeter:
    """A receiving process's CPU time over its measurement, its idle rate taken off.

    Driven by the parent's lines: ``idle`` measures the idle rate (and
    answers), ``mark`` starts the measurement, and the line that asks for the
    results ends it (`spent`).
    """

    def __init__(self) -> None:
        self.idle_rate = 0.0
        self._cpu = self._wall = 0.0

    def idle(self) -> None:
        cpu, wall = _cpu_seconds(), time.perf_counter()
        time.sleep(IDLE_SECONDS)
        self.idle_rate = (_cpu_seconds() - cpu) / (time.perf_counter() - wall)
        print("idle", flush=True)

    def mark(self) -> None:
        self._cpu, self._wall = _cpu_seconds(), time.perf_counter()

    def spent(self) -> float:
        """CPU seconds since `mark`, less what the process spends idle in as long."""
        wall = time.perf_counter() - self._wall
        return _cpu_seconds() - self._cpu - self.idle_rate * wall


def _serve_meter(meter: _CpuMeter) -> None:
    """Answer the parent's ``idle`` and ``mark`` lines until the one asking for results."""
    while (line := sys.stdin.readline().strip()) in ("idle", "mark"):
        if line == "idle":
            meter.idle()
        else:
            meter.mark()


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
    meter = _CpuMeter()
    print("ready", flush=True)
    _serve_meter(meter)
    print(json.dumps({"samples": samples, "cpu": meter.spent()}), flush=True)
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
    meter = _CpuMeter()
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
        await asyncio.to_thread(_serve_meter, meter)
        spent = meter.spent()
        print(json.dumps({"stamps": stamps, "ran": ran, "cpu": spent}), flush=True)


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
    message = Int64()  # one message, its number changed: the sender's cost is the publish
    while line := sys.stdin.readline():
        kind, rate = line.split()
        print(json.dumps(_burst(publishers[kind], message, float(rate))), flush=True)
    plain.close()


def _burst(publisher: Any, message: Any, rate: float) -> dict[str, float]:
    """Send ``rate`` messages/s for ``FLOOD_SECONDS``, paced to the millisecond.

    A reliable publisher whose history is full of messages the receiver has
    not acknowledged refuses one (after blocking a while): it counts as lost.
    """
    from rclpy.impl.implementation_singleton import rclpy_implementation

    count = round(rate * FLOOD_SECONDS)
    period = 1.0 / rate
    publish, refused = publisher.publish, 0
    start = time.perf_counter()
    for n in range(count):
        ahead = start + n * period - time.perf_counter()
        if ahead > 0.001:
            time.sleep(ahead)
        message.data = n
        try:
            publish(message)
        except rclpy_implementation.RCLError:  # "cannot publish data": the receiver is behind
            refused += 1
    took = time.perf_counter() - start
    return {"sent": count, "refused": refused, "rate": (count - 1) / took if took else rate}


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


def _start(*modes: str) -> list[subprocess.Popen[str]]:
    """A helper process for each mode, started side by side; returned once all are ready."""
    processes = [
        subprocess.Popen(
            [sys.executable, "-m", "tests.bench.bench_ros2", mode],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        for mode in modes
    ]
    for process in processes:
        assert process.stdout is not None
        assert process.stdout.readline().strip() == "ready"
    return processes


def _send(process: subprocess.Popen[str], line: str) -> None:
    assert process.stdin is not None
    process.stdin.write(line + "\n")
    process.stdin.flush()


def _tell(process: subprocess.Popen[str], line: str) -> str:
    """Send ``line``; return the process's answer."""
    _send(process, line)
    assert process.stdout is not None
    return process.stdout.readline()


# -- rounds --------------------------------------------------------------------------


def _ratios(name: str, ratios: Sequence[float]) -> dict[str, float]:
    """The median of per-round ratios under ``name``, with the lowest and highest round."""
    return {
        name: statistics.median(ratios),
        f"{name}_lo": min(ratios),
        f"{name}_hi": max(ratios),
    }


def _slices(samples: Sequence[float], rounds: int) -> list[Sequence[float]]:
    """``samples`` cut into ``rounds`` consecutive slices of (nearly) equal length."""
    size = len(samples) / rounds
    return [samples[round(i * size) : round((i + 1) * size)] for i in range(rounds)]


def _in_rounds(
    bridge: Sequence[float], plain: Sequence[float], rounds: int = WIRE_ROUNDS
) -> list[tuple[Sequence[float], Sequence[float]]]:
    """Both sides' samples (in the order sent) cut into ``rounds`` rounds."""
    return list(zip(_slices(bridge, rounds), _slices(plain, rounds), strict=True))


def _compared(
    name: str, rounds: Sequence[tuple[Sequence[float], Sequence[float]]]
) -> dict[str, float]:
    """Per-round median and p99 ratios (bridge over plain rclpy) of latency samples."""
    return {
        **_ratios(
            f"ros2_{name}_median_ratio",
            [statistics.median(b) / statistics.median(p) for b, p in rounds],
        ),
        **_ratios(f"ros2_{name}_p99_ratio", [_p99(list(b)) / _p99(list(p)) for b, p in rounds]),
    }


# -- topic -> state -> monitor callback --------------------------------------------------


def _latency_round() -> dict[str, Any]:
    """One round in fresh processes: each side's latencies, and its CPU per message."""
    *started, sender = _start(*(f"{kind}_latency" for kind in KINDS), "send_latency")
    receivers = dict(zip(KINDS, started, strict=True))
    try:
        for receiver in receivers.values():  # both measure their idle rate at once
            _send(receiver, "idle")
        for receiver in receivers.values():
            assert receiver.stdout is not None
            assert receiver.stdout.readline().strip() == "idle"
            _send(receiver, "mark")
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
    plain = got["plain"]["samples"]
    return {
        "bridge": bridge,
        "plain": plain,
        "cpu_bridge": got["bridge"]["cpu"] / max(1, len(bridge)),
        "cpu_plain": got["plain"]["cpu"] / max(1, len(plain)),
    }


def _topic_to_callback() -> dict[str, float]:
    rounds = [_latency_round() for _ in range(LATENCY_ROUNDS)]
    bridge = [s for r in rounds for s in r["bridge"]]
    plain = [s for r in rounds for s in r["plain"]]
    cpu = {kind: [r[f"cpu_{kind}"] * 1e6 for r in rounds] for kind in KINDS}
    return {
        **_stats("topic_to_callback_bridge", bridge),
        **_stats("topic_to_callback_plain_rclpy", plain),
        "topic_to_callback_samples_bridge": float(len(bridge)),
        "topic_to_callback_samples_plain_rclpy": float(len(plain)),
        "topic_to_callback_sent_each": float(LATENCY_N * LATENCY_ROUNDS),
        "topic_to_callback_rounds": float(LATENCY_ROUNDS * LATENCY_SLICES),
        **_compared(
            "topic_to_callback",
            [pair for r in rounds for pair in _in_rounds(r["bridge"], r["plain"], LATENCY_SLICES)],
        ),
        "receive_cpu_bridge_us_per_msg": statistics.median(cpu["bridge"]),
        "receive_cpu_plain_rclpy_us_per_msg": statistics.median(cpu["plain"]),
        **_ratios(
            "ros2_receive_cpu_ratio",
            [b / p for b, p in zip(cpu["bridge"], cpu["plain"], strict=True)],
        ),
    }


# -- publish -> on the wire ----------------------------------------------------------------


async def _publish_to_wire() -> dict[str, float]:
    from std_msgs.msg import Int64

    from pyrobots_aio import Robot
    from pyrobots_aio.ros2 import attach_ros2

    [receiver] = _start("receive_wire")
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
            for n in range(WIRE_N):
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
        **_compared("publish_to_wire", _in_rounds(got["bridge"], got["plain"])),
    }


# -- drive() -> cmd_vel on the wire ---------------------------------------------------------


async def _drive_to_wire() -> dict[str, float]:
    from geometry_msgs.msg import Twist

    from pyrobots_aio.motion import SENSORS
    from pyrobots_aio.ros2 import Ros2Robot

    [receiver] = _start("receive_twists")
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
            for n in range(1, WIRE_N + 1):  # each command's speed, n, tells it apart
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
    arrivals = {kind: {int(float(v)): t for v, t in got[kind].items()} for kind in sent}
    latency = {  # in the order sent: the rounds are consecutive slices of the commands
        kind: [arrivals[kind][n] - sent[kind][n] for n in sorted(arrivals[kind])] for kind in sent
    }
    return {
        **_stats("drive_to_wire_bridge", latency["bridge"]),
        **_stats("drive_to_wire_plain_rclpy", latency["plain"]),
        **_compared("drive_to_wire", _in_rounds(latency["bridge"], latency["plain"])),
    }


# -- flood ------------------------------------------------------------------------------------


class _Search:
    """The highest rate with zero loss: doubled from ``FLOOD_START`` until a loss, then bisected."""

    def __init__(self) -> None:
        self.lossless = 0.0  # the highest rate achieved without loss
        self.lossy = float("inf")  # the lowest rate achieved with a loss
        self.publisher_limited = False
        self.bursts = 0

    @property
    def done(self) -> bool:
        return self.lossy <= self.lossless * FLOOD_RESOLUTION or self.bursts >= FLOOD_BURSTS

    def next_rate(self) -> float:
        if self.lossy == float("inf"):
            return 2 * self.lossless if self.lossless else FLOOD_START
        return (self.lossless * self.lossy) ** 0.5 if self.lossless else self.lossy / 2

    def record(self, wanted: float, achieved: float, lost: int) -> None:
        self.bursts += 1
        if lost:
            self.lossy = min(self.lossy, achieved)
            return
        self.lossless = max(self.lossless, achieved)
        if achieved < 0.9 * wanted:  # the sender's own limit: no higher rate to try
            self.publisher_limited = True
            self.lossy = self.lossless


class _Flood:
    """The flood's three processes: a sender and each side's receiver."""

    def __init__(self) -> None:
        *receivers, self.sender = _start(*(f"{kind}_flood" for kind in KINDS), "send_flood")
        self.receivers = dict(zip(KINDS, receivers, strict=True))
        self.refused = dict.fromkeys(KINDS, 0)  # messages the sender's publisher refused

    def burst(self, kind: str, rate: float) -> tuple[float, int]:
        """One burst at ``rate`` to ``kind``: the rate achieved and the messages lost."""
        burst = json.loads(_tell(self.sender, f"{kind} {rate}"))
        self.refused[kind] += burst["refused"]
        got = int(_tell(self.receivers[kind], str(burst["sent"])))
        return burst["rate"], max(0, burst["sent"] - got)

    def trial(self, kind: str, search: _Search) -> None:
        """The search's next rate; a burst that loses is sent again before it counts."""
        wanted = search.next_rate()
        achieved, lost = self.burst(kind, wanted)
        if lost:
            achieved, lost = self.burst(kind, wanted)
        search.record(wanted, achieved, lost)

    def close(self) -> None:
        for process in (self.sender, *self.receivers.values()):
            assert process.stdin is not None
            process.stdin.close()
            process.wait()


def _flood() -> dict[str, float]:
    flood = _Flood()
    rounds: list[dict[str, _Search]] = []
    order = list(KINDS)
    try:
        for _ in range(FLOOD_ROUNDS):
            searches = {kind: _Search() for kind in KINDS}
            while not all(search.done for search in searches.values()):
                order.reverse()  # neither side always first
                for kind in order:
                    if not searches[kind].done:
                        flood.trial(kind, searches[kind])
            rounds.append(searches)
    finally:
        flood.close()
    rates = {kind: [r[kind].lossless for r in rounds] for kind in KINDS}
    return {
        "flood_seconds_per_burst": FLOOD_SECONDS,
        "flood_rounds": float(FLOOD_ROUNDS),
        "flood_bursts_bridge": float(sum(r["bridge"].bursts for r in rounds)),
        "flood_bursts_plain_rclpy": float(sum(r["plain"].bursts for r in rounds)),
        "flood_publisher_limited": float(
            sum(s.publisher_limited for r in rounds for s in r.values())
        ),
        "flood_refused_bridge": float(flood.refused["bridge"]),
        "flood_refused_plain_rclpy": float(flood.refused["plain"]),
        "ros2_bridge_zero_loss_msgs_per_s": statistics.median(rates["bridge"]),
        "ros2_plain_rclpy_zero_loss_msgs_per_s": statistics.median(rates["plain"]),
        **_ratios(
            "ros2_zero_loss_rate_ratio",
            [b / p if p else 0.0 for b, p in zip(rates["bridge"], rates["plain"], strict=True)],
        ),
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
