"""The node's life: inside ``async with robot``, nothing left after; domains, clocks, health."""

from __future__ import annotations

import asyncio
import contextlib
import os
import threading
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import DEADLINE, next_where, require_rclpy, wait_for

require_rclpy()

from builtin_interfaces.msg import Time  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from rclpy.impl.implementation_singleton import rclpy_implementation  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402

from pyrobots_aio import HealthMonitor, Robot  # noqa: E402
from pyrobots_aio.ros2 import attach_ros2  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

InvalidHandle = rclpy_implementation.InvalidHandle


def native_threads() -> list[str]:
    """The names of every thread of this process, Python's and DDS's (C++) alike."""
    tasks = Path("/proc/self/task")
    names = []
    for task in tasks.iterdir():
        with contextlib.suppress(FileNotFoundError):  # a thread that just ended
            names.append((task / "comm").read_text().strip())
    return sorted(names)


async def run_once(name: str) -> tuple[set[threading.Thread], Any, Any]:
    """Run a robot with a node and a publisher; return its extra threads, its node and context."""
    before = set(threading.enumerate())
    robot = Robot()
    attach_ros2(robot, name)
    async with robot:
        robot.ros2.publisher("/cmd", Twist).publish(Twist())
        during = set(threading.enumerate()) - before
        node = robot.ros2.node
        context = node.context
        assert context.ok()
    return during, node, context


@pytest.mark.asyncio
async def test_shutdown_leaves_no_thread_node_or_context() -> None:
    await run_once("warm_up")  # Fast DDS starts two process-wide threads once, for good
    python_before, native_before = set(threading.enumerate()), native_threads()
    during, node, context = await run_once("executive")
    assert sorted(t.name for t in during) == [
        "pyrobots_aio loop watchdog of MainThread",
        "pyrobots_aio.ros2 executive",
    ]
    assert set(threading.enumerate()) == python_before
    async with asyncio.timeout(DEADLINE):  # the DDS participant's threads end soon after
        await wait_for(lambda: not Counter(native_threads()) - Counter(native_before))
    assert not context.ok()
    with pytest.raises(InvalidHandle, match="destruction was requested"):
        node.get_node_names()


@pytest.mark.asyncio
async def test_a_failed_start_of_the_inner_backend_stops_the_node() -> None:
    class Broken:
        async def start(self, robot: Robot) -> None:
            raise OSError("no such device: /dev/ttyUSB0")

        async def stop(self) -> None:
            raise AssertionError("never started, never stopped")

    before = set(threading.enumerate())
    robot = Robot(backend=Broken())
    ros2 = attach_ros2(robot, "executive")
    with pytest.raises(OSError, match="no such device"):
        await robot.__aenter__()
    assert set(threading.enumerate()) == before
    assert not ros2.is_running


@pytest.mark.asyncio
async def test_the_exit_ends_even_if_the_executor_s_wake_up_is_lost() -> None:
    # A loaded machine once lost the wake-up of executor.shutdown(): the ROS thread slept
    # on in its wait set and the robot's exit joined it forever. Lose it on purpose.
    before = set(threading.enumerate())
    robot = Robot()
    ros2 = attach_ros2(robot, "sleepy")
    async with robot:
        executor = ros2._thread._executor
        executor.shutdown = lambda timeout_sec=None: True  # no wake-up, no shutdown flag
    assert set(threading.enumerate()) == before
    assert not ros2.is_running


@pytest.mark.asyncio
async def test_the_ros_thread_builds_no_timer_at_each_wake_up(
    plain: Callable[..., PlainNode], monkeypatch: pytest.MonkeyPatch
) -> None:
    # A timeout given to spin_once made rclpy build an rcl timer at every wake-up of the
    # executor (one per message): the bound on its wait is the node's own timer instead.
    import rclpy.executors

    built = Counter[str]()

    class CountedTimer(rclpy.executors.Timer):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            built["timer"] += 1
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(rclpy.executors, "Timer", CountedTimer)
    teleop = plain("teleop")
    robot = Robot()
    attach_ros2(robot, "executive", diagnostics_period=None)
    got: asyncio.Queue[Any] = asyncio.Queue()
    loop = asyncio.get_running_loop()
    async with robot, asyncio.timeout(DEADLINE):
        robot.ros2.node.create_subscription(  # through rclpy's executor, on the ROS thread
            Twist, "/teleop", lambda m: loop.call_soon_threadsafe(got.put_nowait, m), 10
        )
        publisher, matched = teleop.publisher("/teleop", Twist)
        await matched.wait()
        for _ in range(20):
            publisher.publish(Twist())
            await got.get()
    assert built["timer"] == 0


@pytest.mark.asyncio
async def test_the_domain_comes_from_ros_domain_id_unless_given() -> None:
    first, second = Robot(), Robot()
    attach_ros2(first, "from_env")
    attach_ros2(second, "given", domain_id=int(os.environ["ROS_DOMAIN_ID"]) + 1)
    async with first, second:
        assert first.ros2.domain_id == int(os.environ["ROS_DOMAIN_ID"])
        assert second.ros2.domain_id == int(os.environ["ROS_DOMAIN_ID"]) + 1


@pytest.mark.asyncio
async def test_remapped_topics_and_namespaces_resolve_as_ros2_does() -> None:
    robot = Robot()
    attach_ros2(robot, "executive", namespace="/robot1", remap={"cmd_vel": "/base/cmd_vel"})
    async with robot:
        assert robot.ros2.publisher("cmd_vel", Twist).topic == "/base/cmd_vel"
        assert robot.ros2.publisher("odom", Twist).topic == "/robot1/odom"
        assert robot.ros2.publisher("~/status", Twist).topic == "/robot1/executive/status"


@pytest.mark.asyncio
async def test_use_sim_time_follows_clock(plain: Callable[..., PlainNode]) -> None:
    simulator = plain("simulator")
    clock, matched = simulator.publisher("/clock", Clock)
    robot = Robot()
    attach_ros2(robot, "executive", use_sim_time=True)
    async with robot, asyncio.timeout(DEADLINE):
        await matched.wait()
        now = robot.ros2.node.get_clock().now
        while now().nanoseconds != 42_000_000_005:  # /clock is best effort: send until heard
            clock.publish(Clock(clock=Time(sec=42, nanosec=5)))
            await asyncio.sleep(0.02)


@pytest.mark.asyncio
async def test_diagnostics_report_stale_then_fresh_state(plain: Callable[..., PlainNode]) -> None:
    monitor = plain("robot_monitor")
    inbox = monitor.inbox("/diagnostics", DiagnosticArray)
    robot = Robot()
    attach_ros2(robot, "executive", diagnostics_period=0.1, stale_after=5.0, health_keys=["v"])
    name = "/executive: state"

    def ours(array: Any) -> bool:
        return bool(array.status) and array.status[0].name == name

    async with robot, asyncio.timeout(DEADLINE):
        stale = (await next_where(inbox, ours)).status[0]
        assert (stale.level, stale.message, stale.hardware_id) == (
            b"\x03",
            "stale: v (never written)",
            "/executive",
        )
        assert [(v.key, v.value) for v in stale.values] == [("v", "never written")]
        robot.state.v = 0.2
        fresh = (
            await next_where(inbox, lambda a: ours(a) and a.status[0].level == b"\x00")
        ).status[0]
        assert fresh.message == "1 state keys fresh"


@pytest.mark.asyncio
async def test_diagnostics_publish_the_health_monitor_and_the_emergency_stop(
    plain: Callable[..., PlainNode],
) -> None:
    monitor = plain("robot_monitor")
    inbox = monitor.inbox("/diagnostics", DiagnosticArray)
    robot = Robot()
    ros2 = attach_ros2(robot, "executive", diagnostics_period=0.1)
    health = HealthMonitor(robot)
    health.watch("battery", check=lambda level: "warn" if level < 0.2 else "ok")
    health.subsystem("camera")
    ros2.publish_health(health)

    def statuses(array: Any) -> dict[str, Any]:
        return {status.name: status for status in array.status}

    async with robot, asyncio.timeout(DEADLINE):
        health.start()
        robot.state.battery = 0.1
        health.beat("camera", "error", "no frames")
        seen = statuses(await next_where(inbox, lambda a: "/executive: battery" in statuses(a)))
        battery, camera = seen["/executive: battery"], seen["/executive: camera"]
        assert (battery.level, camera.level, camera.message) == (b"\x01", b"\x02", "no frames")
        assert ("state key", "battery") in [(v.key, v.value) for v in battery.values]
        assert "/executive: emergency stop" not in seen
        robot.emergency_stop("cliff")
        latched = statuses(
            await next_where(inbox, lambda a: "/executive: emergency stop" in statuses(a))
        )["/executive: emergency stop"]
        assert (latched.level, latched.message) == (b"\x02", "latched: cliff")


def test_health_needs_diagnostics() -> None:
    ros2 = attach_ros2(Robot(), "executive", diagnostics_period=None)
    with pytest.raises(ValueError, match=r"publishes no /diagnostics \(diagnostics_period=None\)"):
        ros2.publish_health(HealthMonitor(Robot()))


def test_publish_health_takes_a_health_monitor() -> None:
    ros2 = attach_ros2(Robot(), "executive")
    with pytest.raises(TypeError, match=r"publish_health takes a HealthMonitor, got 'battery'"):
        ros2.publish_health("battery")  # type: ignore[arg-type]
