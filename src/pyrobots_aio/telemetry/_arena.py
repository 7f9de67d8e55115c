"""The arena in Foxglove's 3D panel: a world's floor plan as a ``foxglove.SceneUpdate``.

A simulated robot's world (`pyrobots_aio.sim.SimWorld.floor_plan`) lists its
static shapes: walls, obstacles, the dock. Each becomes one entity of the
scene, in ``map``, named after its shape (``wall_north`` ...): a cube for a
box, a cylinder for a circle, in the shape's colour, standing its height on
the floor. The entities never expire, so one message draws the arena for the
whole run.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from ._wellknown import POSE, TIME, VECTOR3, numbers, planar_pose, stamp

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

__all__ = ["ARENA", "SCENE_UPDATE", "SCENE_UPDATE_SCHEMA", "floor_plan", "scene_update"]

ARENA = "/pyrobots/arena"
"""The topic of the arena's scene."""
SCENE_UPDATE = "foxglove.SceneUpdate"
"""Foxglove's well-known schema of a 3D scene: the arena's walls, obstacles and dock."""
DEFAULT_HEIGHT = 0.1
"""Metres a shape stands when its floor plan gives no height (recordings made before heights)."""
_GREY = (0.6, 0.6, 0.6, 1.0)
_PRIMITIVES = ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models")
"""Every primitive list of a ``foxglove.SceneEntity`` (each present, most of them empty)."""

_COLOR = numbers("foxglove.Color", "rgba")
_CUBE = {
    "title": "foxglove.CubePrimitive",
    "type": "object",
    "properties": {"pose": POSE, "size": VECTOR3, "color": _COLOR},
    "required": ["pose", "size", "color"],
}
_CYLINDER = {
    "title": "foxglove.CylinderPrimitive",
    "type": "object",
    "properties": {
        "pose": POSE,
        "size": VECTOR3,
        "bottom_scale": {"type": "number"},
        "top_scale": {"type": "number"},
        "color": _COLOR,
    },
    "required": ["pose", "size", "bottom_scale", "top_scale", "color"],
}
_ENTITY = {
    "title": "foxglove.SceneEntity",
    "type": "object",
    "properties": {
        "timestamp": TIME,
        "frame_id": {"type": "string"},
        "id": {"type": "string"},
        "lifetime": {**TIME, "title": "duration"},
        "frame_locked": {"type": "boolean"},
        "metadata": {
            "type": "array",
            "items": {
                "title": "foxglove.KeyValuePair",
                "type": "object",
                "properties": {"key": {"type": "string"}, "value": {"type": "string"}},
                "required": ["key", "value"],
            },
        },
        "cubes": {"type": "array", "items": _CUBE},
        "cylinders": {"type": "array", "items": _CYLINDER},
        **{name: {"type": "array"} for name in _PRIMITIVES if name not in {"cubes", "cylinders"}},
    },
    "required": ["timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata"],
}
SCENE_UPDATE_SCHEMA: dict[str, Any] = {
    "title": SCENE_UPDATE,
    "type": "object",
    "properties": {
        "deletions": {"type": "array"},
        "entities": {"type": "array", "items": _ENTITY},
    },
    "required": ["deletions", "entities"],
}
"""The JSON schema of the arena's messages (the parts of Foxglove's that they use)."""


def floor_plan(robot: object) -> list[dict[str, Any]]:
    """The static shapes of ``robot``'s world, if it has one (``SimRobot.world.floor_plan()``)."""
    world = getattr(robot, "world", None)
    plan = getattr(world, "floor_plan", None)
    return list(plan()) if callable(plan) else []


def _finite(value: object, default: float) -> float:
    """``value`` if it is a finite number, else ``default``."""
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    return float(value) if ok else default  # type: ignore[arg-type]


def _number(shape: Mapping[str, Any], key: str, default: float) -> float:
    return _finite(shape.get(key), default)


def _color(shape: Mapping[str, Any]) -> dict[str, float]:
    rgba = shape.get("rgba")
    if not (isinstance(rgba, list) and len(rgba) == 4):
        rgba = _GREY
    return {c: _finite(v, grey) for c, v, grey in zip("rgba", rgba, _GREY, strict=True)}


def _primitive(shape: Mapping[str, Any]) -> tuple[str, dict[str, Any]] | None:
    """The cube or cylinder of one floor-plan shape (None: neither a box nor a circle)."""
    height = _number(shape, "height", DEFAULT_HEIGHT)
    pose = planar_pose(
        _number(shape, "x", 0.0),
        _number(shape, "y", 0.0),
        _number(shape, "z", height / 2),
        _number(shape, "yaw", 0.0),
    )
    half = shape.get("half")
    if shape.get("shape") == "box" and isinstance(half, list) and len(half) == 2:
        hx, hy = (_finite(h, 0.0) for h in half)
        size = {"x": 2 * hx, "y": 2 * hy, "z": height}
        return "cubes", {"pose": pose, "size": size, "color": _color(shape)}
    if shape.get("shape") == "circle":
        diameter = 2 * _number(shape, "radius", 0.0)
        cylinder: dict[str, Any] = {"pose": pose}
        cylinder["size"] = {"x": diameter, "y": diameter, "z": height}
        cylinder.update(bottom_scale=1.0, top_scale=1.0, color=_color(shape))
        return "cylinders", cylinder
    return None


def scene_update(shapes: Iterable[Mapping[str, Any]], log_time: int) -> dict[str, Any]:
    """The ``foxglove.SceneUpdate`` that draws ``shapes`` (a floor plan) in ``map``, for good.

    Each shape is an entity named after it (its ``kind`` in the entity's
    metadata), stamped ``log_time`` (ns since 1970); a shape that is neither a
    box nor a circle is left out.
    """
    entities = []
    for index, shape in enumerate(shapes):
        primitive = _primitive(shape)
        if primitive is None:
            continue
        entity: dict[str, Any] = {"timestamp": stamp(log_time), "frame_id": "map"}
        entity.update(
            id=str(shape.get("name", f"shape{index}")),
            lifetime={"sec": 0, "nsec": 0},  # never expires
            frame_locked=False,
            metadata=[{"key": "kind", "value": str(shape.get("kind", "obstacle"))}],
        )
        entity.update({name: [] for name in _PRIMITIVES})
        entity[primitive[0]] = [primitive[1]]
        entities.append(entity)
    return {"deletions": [], "entities": entities}
