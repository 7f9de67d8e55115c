"""Dead reckoning from the wheel encoders, as the robot's firmware does it."""

from __future__ import annotations

import math

from ..lowlevel import wrap_angle

__all__ = ["Odometry"]


class Odometry:
    """Dead reckoning from the wheel encoders, as the robot's firmware does it.

    Args:
        radius: The wheel radius (m).
        track: The distance between the wheels (m).
        left: The left encoder now (rad).
        right: The right encoder now (rad).
    """

    __slots__ = ("_left", "_radius", "_right", "_track", "x", "y", "yaw")

    def __init__(self, radius: float, track: float, left: float, right: float) -> None:
        self._radius, self._track = radius, track
        self.reset(left, right)

    def reset(self, left: float, right: float) -> None:
        """Restart at the origin, with the encoders reading ``left`` and ``right``."""
        self.x = self.y = self.yaw = 0.0
        self._left, self._right = left, right

    def update(self, left: float, right: float) -> None:
        """Move by what the encoders turned since the last call, as one circular arc."""
        d_left = (left - self._left) * self._radius
        d_right = (right - self._right) * self._radius
        self._left, self._right = left, right
        distance = (d_left + d_right) / 2
        turn = (d_right - d_left) / self._track
        # Exact for a circular arc: the chord, along the mean heading.
        chord = distance if abs(turn) < 1e-12 else 2 * distance / turn * math.sin(turn / 2)
        heading = self.yaw + turn / 2
        self.x += chord * math.cos(heading)
        self.y += chord * math.sin(heading)
        self.yaw = wrap_angle(self.yaw + turn)
