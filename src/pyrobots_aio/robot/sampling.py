"""Sampling a robot's state and pose at each write of its state (recorders, the live view).

A simulated robot writes every sensor in one batch per control tick, so a
sampler subscribed to the state sees each tick once: it passes on the values
that changed (or, downsampled, those due) and the pose of a frame in ``map``.
The recorders (`pyrobots_aio.recording`) and ``Robot(serve=...)`` share it, so
a recording and the live view carry the same samples.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .._exceptions import UnknownFrameError

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from ..state import Subscription
    from ._robot import Robot

__all__ = ["POSE_EPSILON", "Pose2D", "StateSampler"]

Pose2D = tuple[float, float, float]
"""``(x, y, yaw)`` in the map frame (metres, radians)."""
_MISSING = object()
POSE_EPSILON = 1e-9
"""A pose that moved less than this (metres and radians) is not sampled again."""


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _same(old: object, new: object) -> bool:
    """Whether a sample would repeat the last one (only plain scalars are compared)."""
    if type(old) is not type(new) or not isinstance(new, bool | int | float | str | None):
        return False
    return old == new


class StateSampler:
    """Calls ``sink(time, values, pose)`` for each write of a robot's state that brings news.

    Args:
        sink: Receives the loop time of the write, the watched values that
            changed (or are due), and the pose (None if not due or not known).
        keys: The keys to pass on (None: every key).
        period: Least seconds between two samples of a number, or of the pose
            (0: every change). Discrete values (booleans, strings ...) are passed
            on at every change whatever the period.
        pose_frame: The frame whose pose in ``map`` goes with each write (None: none).
    """

    def __init__(
        self,
        sink: Callable[[float, dict[str, object], Pose2D | None], None],
        *,
        keys: frozenset[str] | None = None,
        period: float = 0.0,
        pose_frame: str | None = "base_link",
    ) -> None:
        self._sink = sink
        self._watched = keys
        self._period = period
        self.pose_frame = pose_frame
        self._robot: Robot | None = None
        self._subscription: Subscription | None = None
        self._values: dict[str, object] = {}
        self._stamps: dict[str, float] = {}
        self._pose: Pose2D | None = None
        self._pose_stamp = -math.inf

    def start(self, robot: Robot) -> None:
        """Sample ``robot`` from now on, starting with the values it holds.

        The pose is sampled only if ``robot.poses`` knows the frame now
        (`pose_frame` is set to None otherwise).
        """
        self._robot = robot
        frame = self.pose_frame
        self.pose_frame = frame if frame is not None and frame in robot.poses.frames() else None
        if self._watched is not None and not self._watched and self.pose_frame is None:
            return
        store = robot.state
        self._subscription = store.subscribe(self._on_write, keys=None)
        present = {key: store[key] for key in store}
        if present:
            self._on_write(present)

    def stop(self) -> None:
        """Stop sampling."""
        if self._subscription is not None:
            self._subscription.close()
            self._subscription = None
        self._robot = None

    def _on_write(self, changes: Mapping[str, object]) -> None:
        robot = self._robot
        if robot is None or not changes:
            return
        now = robot.state.timestamp(next(iter(changes)))
        watched, values, stamps, period = self._watched, self._values, self._stamps, self._period
        due: dict[str, object] = {}
        for key, value in changes.items():
            if watched is not None and key not in watched:
                continue
            old = values.get(key, _MISSING)
            if old is not _MISSING:
                if _same(old, value):
                    continue
                if period and _is_number(value) and now - stamps[key] < period:
                    continue
            values[key] = value
            stamps[key] = now
            due[key] = value
        pose = self._pose_due(robot, now) if self.pose_frame is not None else None
        if due or pose is not None:
            self._sink(now, due, pose)

    def _pose_due(self, robot: Robot, now: float) -> Pose2D | None:
        if now - self._pose_stamp < self._period or self.pose_frame is None:
            return None
        try:
            matrix = robot.poses.get_transform(self.pose_frame)
        except UnknownFrameError:
            return None
        yaw = math.atan2(float(matrix[1, 0]), float(matrix[0, 0]))
        pose = (float(matrix[0, 3]), float(matrix[1, 3]), yaw)
        old = self._pose
        still = old is not None and all(
            abs(a - b) < POSE_EPSILON for a, b in zip(old, pose, strict=True)
        )
        if still or not all(math.isfinite(c) for c in pose):
            return None
        self._pose, self._pose_stamp = pose, now
        return pose
