"""The small arithmetic of the motion layer: checked numbers, angles, speed ramps, speed limits."""

from __future__ import annotations

import math

from .._core._numbers import finite

GAIN = 3.0
"""Per second: a ramp's speed is this times the remaining way, between its floor and top."""
MAX_DISTANCE = 100_000.0
"""Metres: the longest `DriveBase.drive_distance` (and `DriveBase.navigate_to` goal) allowed.

100 km, far beyond any battery's charge: a larger number is a units mistake,
and it would never finish (odometry's floats lose the tolerance long before).
"""
MAX_TURN = 2000 * math.pi
"""Radians: the largest `DriveBase.rotate_angle` allowed either way (1000 turns).

``rotate_angle(4 * math.pi)`` turns twice, as asked; ``rotate_angle(1e300)``
is refused rather than spinning forever.
"""


def checked(
    name: str,
    value: float,
    *,
    positive: bool = False,
    bound: float | None = None,
    fix: str | None = None,
) -> float:
    """Return ``value`` as a float, or raise a `ValueError` naming ``name`` and the value.

    ``bound``: the largest magnitude allowed, if any; ``fix``: what the message
    suggests.

    Examples:
        >>> checked("speed", 0.2, positive=True)
        0.2
    """
    low = None if bound is None else -bound
    return finite(name, value, positive=positive, low=low, high=bound, fix=fix)


def wrap_angle(angle: float) -> float:
    """Return ``angle`` (radians) wrapped into ``[-pi, pi]``."""
    return math.atan2(math.sin(angle), math.cos(angle))


def ramp(remaining: float, top: float, floor: float) -> float:
    """Speed toward a goal ``remaining`` away: full speed, slowing down near it.

    Examples:
        >>> ramp(1.0, 0.2, 0.03), ramp(-0.01, 0.2, 0.03)
        (0.2, -0.03)
    """
    return math.copysign(min(top, max(floor, GAIN * abs(remaining))), remaining)


def limit_speeds(v: float, w: float, half_track: float, top: float) -> tuple[float, float]:
    """``(v, w)`` scaled down as a whole so that neither wheel runs faster than ``top`` (m/s).

    Scaling both keeps the commanded curvature (the robot follows the same
    arc, slower), as a differential-drive firmware does. Any finite numbers
    work, up to ``1.7e308``: the wheel speeds are worked out at a unit scale
    first, so nothing overflows into infinity or NaN.

    Examples:
        >>> limit_speeds(0.2, 0.0, 0.1175, 0.306), limit_speeds(1.7e308, 0.0, 0.1175, 0.306)
        ((0.2, 0.0), (0.306, 0.0))
    """
    size = max(abs(v), abs(w), 1.0)
    unit_v, unit_w = v / size, w / size
    fastest = max(abs(unit_v - unit_w * half_track), abs(unit_v + unit_w * half_track))
    if fastest * size <= top:
        return v, w
    scale = top / fastest
    return unit_v * scale, unit_w * scale
