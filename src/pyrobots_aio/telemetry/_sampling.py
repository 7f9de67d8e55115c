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

    from ..poses import Pose2D
    from ..state import Subscription
    from ._source import TelemetrySource

__all__ = ["POSE_EPSILON", "StateSampler"]

_MISSING = object()
POSE_EPSILON = 1e-9
"""A pose that moved less than this (metres and radians) is not sampled again."""


_SCALARS = frozenset({bool, int, float, str, type(None)})
"""Types whose equal values are the same sample (others, numpy arrays ..., always count)."""


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
        # The watched keys in a fixed order: looked up in each write (a few of its many keys)
        self._order = None if keys is None else tuple(sorted(keys))
        self._period = period
        self.pose_frame = pose_frame
        # What each write asks of the robot, bound once at `start`: the write's time, the pose.
        self._stamp: Callable[[str], float] | None = None
        self._planar: Callable[[str], tuple[float, float, float]] | None = None
        self._subscription: Subscription | None = None
        self._values: dict[str, object] = {}
        self._stamps: dict[str, float] = {}
        self._pose: Pose2D | None = None
        self._pose_stamp = -math.inf

    def start(self, robot: TelemetrySource) -> None:
        """Sample ``robot`` from now on, starting with the values it holds.

        The pose is sampled only if ``robot.poses`` knows the frame now
        (`pose_frame` is set to None otherwise).
        """
        self._stamp, self._planar = robot.state.timestamp, robot.poses.planar
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
        self._stamp = self._planar = None

    def _on_write(self, changes: Mapping[str, object]) -> None:
        # Runs at every write of the state (every control tick of a simulated robot).
        stamp = self._stamp
        if stamp is None or not changes:
            return
        order = self._order
        keys = changes if order is None else order
        now = stamp(next(iter(changes)))
        values, stamps, period = self._values, self._stamps, self._period
        due: dict[str, object] = {}
        for key in keys:
            if key not in changes:  # a watched key this write does not have
                continue
            value = changes[key]
            old = values.get(key, _MISSING)
            if old is not _MISSING:
                kind = type(value)
                if kind is type(old) and kind in _SCALARS and old == value:
                    continue  # the same sample again
                if (  # a number sampled less than a period ago (downsampling only)
                    period
                    and kind is not bool
                    and isinstance(value, int | float)
                    and now - stamps[key] < period
                ):
                    continue
            values[key] = value
            if period:
                stamps[key] = now
            due[key] = value
        pose = None
        frame = self.pose_frame
        if frame is not None and now - self._pose_stamp >= period:
            try:
                x, y, yaw = self._planar(frame)  # type: ignore[misc]  # (set with _stamp)
            except UnknownFrameError:
                pass
            else:
                old_pose = self._pose
                if (
                    old_pose is None
                    or abs(old_pose[0] - x) >= POSE_EPSILON
                    or abs(old_pose[1] - y) >= POSE_EPSILON
                    or abs(old_pose[2] - yaw) >= POSE_EPSILON
                ) and (x - x) + (y - y) + (yaw - yaw) == 0.0:  # moved, and finite
                    pose = self._pose = (x, y, yaw)
                    self._pose_stamp = now
        if due or pose is not None:
            self._sink(now, due, pose)
