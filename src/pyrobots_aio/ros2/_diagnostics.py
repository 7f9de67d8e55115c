"""``/diagnostics`` from the robot's health: how fresh the state keys it watches are.

A minimal health report, for any ROS 2 tool (``rqt_robot_monitor``, the
diagnostic aggregator): one ``diagnostic_msgs/DiagnosticStatus`` named after
the node, ``STALE`` while a watched key is older than ``stale_after`` (or
was never written), ``OK`` otherwise, with each key's age as a value. The
watched keys are those the node's subscriptions write, plus any given. It is
published every ``period`` seconds of the robot's clock.

Beside it: an ``ERROR`` status ``"<node>: emergency stop"`` while the robot's
emergency stop is latched, and one status per thing each `HealthMonitor`
given to ``robot.ros2.publish_health(monitor)`` watches (its level, message
and last heartbeat), named ``"<node>: <name>"``.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

from ._rclpy import rclpy_module

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from ..robot import Robot
    from ..supervision import HealthMonitor

OK, ERROR, STALE = 0, 2, 3  # diagnostic_msgs/DiagnosticStatus levels (bytes on the wire)


def staleness(
    robot: Robot, keys: Iterable[str], stale_after: float
) -> tuple[int, str, list[tuple[str, str]]]:
    """The level, message and per-key ages of the watched ``keys`` now.

    Examples:
        >>> from pyrobots_aio import Robot
        >>> robot = Robot()
        >>> staleness(robot, ["odom"], 1.0)
        (3, 'stale: odom (never written)', [('odom', 'never written')])
    """
    now = robot.time() if robot.is_running else None
    stale: list[str] = []
    values: list[tuple[str, str]] = []
    for key in sorted(keys):
        if key not in robot.state or now is None:
            age_text, old = "never written", True
        else:
            age = now - robot.state.timestamp(key)
            age_text, old = f"{age:.3f} s", age > stale_after
        values.append((key, age_text))
        if old:
            stale.append(f"{key} ({age_text})")
    if stale:
        return STALE, "stale: " + ", ".join(stale), values
    fresh = f"{len(values)} state keys fresh" if values else "no state keys watched"
    return OK, fresh, values


class Diagnostics:
    """Publishes the node's health on ``/diagnostics`` every ``period`` seconds."""

    def __init__(
        self,
        node: Any,
        robot: Robot,
        *,
        period: float,
        stale_after: float,
        keys: Callable[[], Iterable[str]],
        monitors: list[HealthMonitor],
    ) -> None:
        msgs = rclpy_module("diagnostic_msgs.msg")
        self._msgs = msgs
        self._node, self._robot = node, robot
        self._period, self._stale_after, self._keys = period, stale_after, keys
        self._pub = node.create_publisher(msgs.DiagnosticArray, "/diagnostics", 10)
        self._monitors = monitors  # the node's list: monitors given later are published too
        self._timer: asyncio.TimerHandle | None = None
        self._next = 0.0

    def start(self) -> None:
        """Publish now, then every period."""
        self._next = asyncio.get_running_loop().time()
        self._tick()

    def stop(self) -> None:
        """Stop publishing."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def message(self) -> Any:
        """The ``DiagnosticArray`` describing the robot now."""
        level, text, values = staleness(self._robot, self._keys(), self._stale_after)
        statuses = [self._status(level, "state", text, values)]
        reason = self._robot.emergency_stop_reason
        if reason is not None:
            statuses.append(self._status(ERROR, "emergency stop", f"latched: {reason}", []))
        now = self._robot.time()
        for monitor in self._monitors:
            for health in monitor.statuses().values():
                last = health.last_seen
                seen = "never" if last is None else f"{now - last:.3f} s ago"
                facts = [("level", health.level.value), ("last heartbeat", seen)]
                if health.key is not None:
                    facts.append(("state key", health.key))
                statuses.append(
                    self._status(health.level.diagnostic, health.name, health.message, facts)
                )
        array = self._msgs.DiagnosticArray(status=statuses)
        array.header.stamp = self._node.get_clock().now().to_msg()
        return array

    def _status(self, level: int, what: str, text: str, values: list[tuple[str, str]]) -> Any:
        msgs, name = self._msgs, self._node.get_fully_qualified_name()
        return msgs.DiagnosticStatus(
            level=bytes([level]),
            name=f"{name}: {what}",
            message=text,
            hardware_id=name,
            values=[msgs.KeyValue(key=key, value=value) for key, value in values],
        )

    def _tick(self) -> None:
        self._pub.publish(self.message())
        loop = asyncio.get_running_loop()
        self._next += self._period
        self._timer = loop.call_at(self._next, self._tick)
