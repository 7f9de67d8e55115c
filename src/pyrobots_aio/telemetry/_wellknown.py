"""The parts of Foxglove's well-known schemas that several messages share: times, vectors, poses.

Foxglove recognises its well-known schemas by name (``foxglove.PoseInFrame``
...), whatever the encoding; these are their JSON schema pieces and the JSON
values that fill them.
"""

from __future__ import annotations

import math
from typing import Any

TIME: dict[str, Any] = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
    },
}


def numbers(title: str, names: str) -> dict[str, Any]:
    """The JSON schema of an object of numbers, one per letter of ``names``, all required."""
    return {
        "title": title,
        "type": "object",
        "properties": {name: {"type": "number"} for name in names},
        "required": list(names),
    }


VECTOR3, QUATERNION = numbers("foxglove.Vector3", "xyz"), numbers("foxglove.Quaternion", "xyzw")
POSE: dict[str, Any] = {
    "title": "foxglove.Pose",
    "type": "object",
    "properties": {"position": VECTOR3, "orientation": QUATERNION},
    "required": ["position", "orientation"],
}


def stamp(ns: int) -> dict[str, int]:
    """A ``time`` value: ``ns`` nanoseconds since 1970 as seconds and nanoseconds."""
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def quaternion(yaw: float) -> dict[str, float]:
    """The ``foxglove.Quaternion`` of a turn of ``yaw`` radians about the vertical."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def planar_pose(x: float, y: float, z: float, yaw: float) -> dict[str, Any]:
    """A ``foxglove.Pose`` at ``(x, y, z)``, turned ``yaw`` radians about the vertical."""
    return {"position": {"x": x, "y": y, "z": z}, "orientation": quaternion(yaw)}
