"""The small arithmetic of the motion layer: checked numbers, angles, speed ramps."""

from __future__ import annotations

import math

GAIN = 3.0
"""Per second: a ramp's speed is this times the remaining way, between its floor and top."""


def checked(name: str, value: float, *, positive: bool = False) -> float:
    """Return ``value`` as a float, or raise a `ValueError` naming ``name`` and the value.

    Example:
        >>> checked("speed", 0.2, positive=True)
        0.2
    """
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        msg = f"{name} must be a finite number, got {value!r}"
        raise ValueError(msg)
    if positive and value <= 0:
        msg = f"{name} must be positive, got {value!r}"
        raise ValueError(msg)
    return float(value)


def wrap_angle(angle: float) -> float:
    """Return ``angle`` (radians) wrapped into ``[-pi, pi]``."""
    return math.atan2(math.sin(angle), math.cos(angle))


def ramp(remaining: float, top: float, floor: float) -> float:
    """Speed toward a goal ``remaining`` away: full speed, slowing down near it.

    Example:
        >>> ramp(1.0, 0.2, 0.03), ramp(-0.01, 0.2, 0.03)
        (0.2, -0.03)
    """
    return math.copysign(min(top, max(floor, GAIN * abs(remaining))), remaining)
