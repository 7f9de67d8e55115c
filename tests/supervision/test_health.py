"""HealthMonitor: heartbeats, staleness on timers, levels in robot.state, a read API."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest

from log_support import logged
from pyrobots_aio import HealthMonitor, Outcome, Robot, StateError
from pyrobots_aio.supervision import HealthLevel, HealthStatus

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


async def publish(robot: Robot, key: str, rate: float, until: float) -> None:
    """Write ``key`` at ``rate`` Hz until loop time ``until``."""
    while robot.time() < until - 1e-9:
        robot.state[key] = robot.time()
        await asyncio.sleep(1 / rate)


class Changes:
    """Every write of some state keys, as (time, key, value)."""

    def __init__(self, robot: Robot, *keys: str) -> None:
        self.seen: list[tuple[float, str, Any]] = []
        robot.state.subscribe(
            lambda changes: self.seen.extend(
                (round(robot.time(), 6), key, value) for key, value in changes.items()
            ),
            keys=keys,
        )


async def test_a_stream_that_slows_down_warns_then_goes_stale_then_recovers() -> None:
    async with Robot() as robot:
        robot.state.camera = 0.0
        changes = Changes(robot, "health_camera", "health")
        health = HealthMonitor(robot)
        health.watch("camera", warn_after=0.05, stale_after=0.5)
        monitor = health.start()
        assert (robot.state.health_camera, robot.state.health) == ("ok", "ok")
        await publish(robot, "camera", 40, until=1.0)  # every 25 ms: fine
        await publish(robot, "camera", 5, until=2.0)  # every 200 ms: warn after each 50 ms
        await robot.sleep(1.0)  # silence: stale 500 ms after the last frame
        await publish(robot, "camera", 40, until=3.5)
        assert monitor.outcome is Outcome.NOT_DONE
    assert changes.seen == [
        (0.0, "health_camera", "ok"),
        (0.0, "health", "ok"),
        (1.05, "health_camera", "warn"),  # the 5 Hz stream's first frame is at 1.0
        (1.05, "health", "warn"),
        (1.2, "health_camera", "ok"),
        (1.2, "health", "ok"),
        (1.25, "health_camera", "warn"),
        (1.25, "health", "warn"),
        (1.4, "health_camera", "ok"),
        (1.4, "health", "ok"),
        (1.45, "health_camera", "warn"),
        (1.45, "health", "warn"),
        (1.6, "health_camera", "ok"),
        (1.6, "health", "ok"),
        (1.65, "health_camera", "warn"),
        (1.65, "health", "warn"),
        (1.8, "health_camera", "ok"),
        (1.8, "health", "ok"),
        (1.85, "health_camera", "warn"),
        (1.85, "health", "warn"),
        (2.3, "health_camera", "stale"),  # 500 ms after the frame at 1.8
        (2.3, "health", "stale"),
        (3.0, "health_camera", "ok"),
        (3.0, "health", "ok"),
    ]


async def test_staleness_costs_one_timer_call_per_threshold_not_one_per_write() -> None:
    calls = []
    async with Robot() as robot:
        robot.state.lidar = 0.0
        health = HealthMonitor(robot)
        health.watch("lidar", warn_after=0.5, stale_after=2.0)
        due = health._due

        def counted(watched: Any) -> None:
            calls.append(robot.time())
            due(watched)

        health._due = counted  # type: ignore[method-assign]
        health.start()
        await publish(robot, "lidar", 50, until=10.0)  # 500 writes
        fresh = len(calls)
        await robot.sleep(100.0)
        stale = len(calls)
        await robot.sleep(100.0)
        assert len(calls) == stale  # stale: no timer at all
    assert 19 <= fresh <= 21  # one every 0.5 s, re-armed on the latest write
    assert stale - fresh <= 3  # the last re-arm, warn, stale
    assert robot.state.health_lidar == "stale"


async def test_a_subsystem_beats_and_reports_its_own_level() -> None:
    async with Robot() as robot:
        health = HealthMonitor(robot, prefix="diag")
        health.subsystem("arm", stale_after=1.0)
        health.subsystem("gripper")  # no deadline: reports only
        health.start()
        assert robot.state.diag_arm == "stale"  # no beat yet
        assert robot.state.diag == "stale"
        health.beat("arm")
        health.beat("gripper", HealthLevel.WARN, "slipping")
        assert (robot.state.diag_arm, robot.state.diag_gripper) == ("ok", "warn")
        assert robot.state.diag == "warn"
        health.beat("gripper", "error", "jammed")
        assert robot.state.diag == "error"
        await robot.sleep(1.0)
        assert robot.state.diag_arm == "stale"
        assert robot.state.diag == "stale"  # stale ranks above error, as in diagnostic_msgs
        statuses = health.statuses()
        assert statuses["arm"] == HealthStatus(
            "arm", HealthLevel.STALE, "no heartbeat for 1 s", None, 1.0, 0.0
        )
        assert statuses["gripper"] == HealthStatus(
            "gripper", HealthLevel.ERROR, "jammed", None, 0.0, 0.0
        )
        assert health.level is HealthLevel.STALE


async def test_a_check_grades_the_values_written() -> None:
    def battery(level: float) -> HealthLevel | tuple[HealthLevel, str]:
        if level < 0.1:
            return HealthLevel.ERROR, f"battery at {level:.0%}"
        return (HealthLevel.WARN, "battery low") if level < 0.2 else HealthLevel.OK

    async with Robot() as robot:
        robot.state.battery = 0.5
        health = HealthMonitor(robot)
        health.watch("battery", check=battery)
        health.start()
        levels = []
        for charge in (0.5, 0.15, 0.05, 0.3):
            robot.state.battery = charge
            levels.append((robot.state.health_battery, health.statuses()["battery"].message))
        assert levels == [
            ("ok", ""),
            ("warn", "battery low"),
            ("error", "battery at 5%"),
            ("ok", ""),
        ]
        await robot.sleep(3600)  # no deadline given: never stale
        assert robot.state.health_battery == "ok"


async def test_a_check_that_raises_is_an_error(caplog: pytest.LogCaptureFixture) -> None:
    async with Robot() as robot:
        robot.state.temperature = "hot"
        health = HealthMonitor(robot)
        health.watch("temperature", check=lambda t: HealthLevel.OK if t < 60 else HealthLevel.ERROR)
        health.start()
        assert robot.state.health_temperature == "error"
        assert health.statuses()["temperature"].message == (
            "check failed: TypeError(\"'<' not supported between instances of 'str' and 'int'\")"
        )
    assert "health check" in logged(caplog)[0].getMessage()


async def test_a_transition_triggers_an_action() -> None:
    async with Robot() as robot:
        robot.state.camera = 0.0
        health = HealthMonitor(robot)
        health.watch("camera", stale_after=0.5)
        health.start()
        robot.whenever("health_camera", becomes="stale").do(robot.emergency_stop, "camera lost")
        await robot.sleep(1.0)
        assert robot.emergency_stop_reason == "camera lost"


async def test_listeners_get_each_change_for_diagnostics() -> None:
    async with Robot() as robot:
        robot.state.odom = 0
        health = HealthMonitor(robot)
        health.watch("odom", name="odometry", warn_after=0.1, stale_after=0.3)
        got: list[tuple[float, str, str]] = []

        def failing(status: HealthStatus) -> None:
            raise RuntimeError("publisher down")

        health.subscribe(failing)
        stop = health.subscribe(lambda s: got.append((round(robot.time(), 6), s.level, s.message)))
        health.start()
        await robot.sleep(0.5)
        robot.state.odom = 1
        stop()
        await robot.sleep(0.5)
    assert got == [
        (0.0, "ok", ""),
        (0.1, "warn", "no heartbeat for 0.1 s"),
        (0.3, "stale", "no heartbeat for 0.3 s"),
        (0.5, "ok", ""),
    ]
    assert HealthLevel.STALE.diagnostic == 3
    assert [level.diagnostic for level in HealthLevel] == [0, 1, 2, 3]


async def test_it_is_an_action_that_the_robot_stops_and_that_can_start_again() -> None:
    async with Robot() as robot:
        robot.state.camera = 0
        health = HealthMonitor(robot)
        health.watch("imu", warn_after=0.1)  # not written yet: stale until it is
        monitor = health.start()
        assert monitor.name == "health_monitor"
        with pytest.raises(StateError, match=r"runs already; start it once$"):
            health.start()
        assert robot.state.health_imu == "stale"
        robot.state.imu = 1
        assert robot.state.health_imu == "ok"
        health.watch("camera", stale_after=1.0)  # added while running: armed at once
        assert robot.state.health_camera == "ok"
        monitor.cancel()
        await monitor.wait_done()
        robot.state.imu = 2
        await robot.sleep(5)
        assert robot.state.health_imu == "ok"  # stopped: nothing changes any more
        assert robot.state.health_camera == "ok"
        again = health.start()
        assert robot.state.health_camera == "stale"  # 5 s without a write
        await robot.sleep(0)
    assert again.outcome is Outcome.CANCELLED  # the robot's exit cancelled it


BAD_CALLS: list[tuple[Any, str]] = [
    (
        lambda h: h.watch("x"),
        "watch('x') needs warn_after=, stale_after= or check=; give at least one",
    ),
    (
        lambda h: h.watch("x", warn_after=2, stale_after=1),
        "warn_after (2.0) must be shorter than stale_after (1.0)",
    ),
    (
        lambda h: h.watch("x", warn_after=-1),
        "warn_after must be a positive number of seconds, got -1",
    ),
    (
        lambda h: h.subsystem("", stale_after=1),
        "a watched name must be a non-empty string, got ''",
    ),
    (
        lambda h: h.subsystem("camera"),
        "'camera' is watched already; give another name= to watch it twice",
    ),
    (
        lambda h: h.beat("wheels"),
        "beat('wheels'): that name is unknown; the subsystems are ['arm']",
    ),
    (
        lambda h: h.beat("camera"),
        "beat('camera'): that name watches the state key 'camera'; the subsystems are ['arm']",
    ),
    (
        lambda h: h.beat("arm", "fine"),
        "unknown health level 'fine'; use a HealthLevel or one of ['ok', 'warn', 'error', 'stale']",
    ),
]


@pytest.mark.parametrize(("call", "message"), BAD_CALLS)
async def test_bad_calls_are_refused(call: Any, message: str) -> None:
    health = HealthMonitor(Robot())
    health.watch("camera", stale_after=1.0)
    health.subsystem("arm")
    with pytest.raises((ValueError, StateError)) as refused:
        call(health)
    assert str(refused.value) == message


async def test_a_bad_prefix_is_refused() -> None:
    with pytest.raises(
        ValueError, match=r"^HealthMonitor prefix must be a non-empty string, got ''$"
    ):
        HealthMonitor(Robot(), prefix="")
