"""The arena in Foxglove's 3D panel: a world's floor plan as a ``foxglove.SceneUpdate``.

A simulated robot's world (`pyrobots_aio.sim.SimWorld.floor_plan`) lists its
static shapes: walls, obstacles, the dock. Each becomes one entity of the
scene, in ``map``, named after its shape (``wall_north`` ...): a cube for a
box, a cylinder for a circle, in the shape's colour, standing its height on
the floor. The entities never expire, so one message draws the arena for the
whole run.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from .._core._numbers import as_float
from ._wellknown import POSE, TIME, VECTOR3, numbers, planar_pose, stamp

if TYPE_CHECKING:
    from collections.abc import Iterable

__all__ = [
    "ARENA",
    "SCENE_UPDATE",
    "SCENE_UPDATE_SCHEMA",
    "FloorShape",
    "floor_plan",
    "scene_update",
]

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


@dataclass(frozen=True, slots=True)
class FloorShape:
    """One static shape of a world's floor plan, seen from above, in ``map`` (metres, radians).

    A floor plan is a list of JSON-friendly dicts (`floor_plan`,
    ``SimWorld.floor_plan``, a recording's header); `read_plan` reads it, once
    for every one who draws it (Foxglove's 3D panel, the replay page's map).
    A box has `half`, a circle its `radius`: exactly one of them is set.

    Examples:
        >>> plan = [{"x": 0}, {"name": "crate", "shape": "box", "x": 1, "y": 2, "half": [0.5, 0.1]}]
        >>> [(s.name, s.kind, s.half, s.radius, s.z) for s in FloorShape.read_plan(plan)]
        [('crate', 'obstacle', (0.5, 0.1), None, 0.05)]
    """

    name: str
    kind: str
    """What it is: its material's name in the shipped arena (``wall``, ``obstacle``, ``dock``)."""
    x: float
    y: float
    yaw: float
    half: tuple[float, float] | None
    """A box's half sides along its own x and y; None for a circle."""
    radius: float | None
    """A circle's radius; None for a box."""
    rgba: tuple[float, float, float, float] | None
    """Its colour (0 to 1 each), if the plan gives one."""
    height: float
    """How tall it stands (`DEFAULT_HEIGHT` if the plan does not say)."""
    z: float
    """The height of its centre (half its height if the plan does not say)."""

    def __post_init__(self) -> None:
        if (self.half is None) == (self.radius is None):
            msg = (
                f"a floor shape is a box or a circle, got half={self.half!r} and "
                f"radius={self.radius!r}; give exactly one of them"
            )
            raise ValueError(msg)

    @classmethod
    def read(cls, raw: object, index: int = 0) -> FloorShape | None:
        """The shape a floor plan's ``index``-th dict describes, or None if it is malformed.

        It must give finite numbers ``x`` and ``y`` (``yaw``: 0 if absent), and
        ``shape``: ``"box"`` with ``half`` ``[hx, hy]``, or ``"circle"`` with a
        ``radius`` of 0 or more. A name defaults to ``shape<index>``, a kind to
        ``obstacle``; an ``rgba`` that is not four finite numbers is left out.
        """
        if not isinstance(raw, Mapping):
            return None
        x, y, yaw = as_float(raw.get("x")), as_float(raw.get("y")), as_float(raw.get("yaw", 0.0))
        half, radius = _numbers(raw.get("half"), 2), as_float(raw.get("radius"))
        box = raw.get("shape") == "box" and half is not None
        circle = raw.get("shape") == "circle" and radius is not None and radius >= 0
        if x is None or y is None or yaw is None or not (box or circle):
            return None
        height = as_float(raw.get("height"))
        height = DEFAULT_HEIGHT if height is None else height
        z = as_float(raw.get("z"))
        rgba = _numbers(raw.get("rgba"), 4)
        return cls(
            name=str(raw.get("name", f"shape{index}")),
            kind=str(raw.get("kind", "obstacle")),
            x=x, y=y, yaw=yaw,
            half=(half[0], half[1]) if box and half is not None else None,
            radius=radius if not box else None,
            rgba=(rgba[0], rgba[1], rgba[2], rgba[3]) if rgba is not None else None,
            height=height,
            z=height / 2 if z is None else z,
        )  # fmt: skip

    @classmethod
    def read_plan(cls, plan: Iterable[object]) -> list[FloorShape]:
        """Every well-formed shape of ``plan``, in its order (the malformed ones left out)."""
        return [shape for i, raw in enumerate(plan) if (shape := cls.read(raw, i)) is not None]


def _numbers(value: object, count: int) -> list[float] | None:
    """``value`` as ``count`` finite floats, if it is a list or tuple of that many."""
    if not isinstance(value, list | tuple) or len(value) != count:
        return None
    numbers = [as_float(v) for v in value]
    return None if None in numbers else cast("list[float]", numbers)


def _color(shape: FloorShape) -> dict[str, float]:
    return dict(zip("rgba", shape.rgba or _GREY, strict=True))


def _primitive(shape: FloorShape) -> tuple[str, dict[str, Any]]:
    """The cube or cylinder that draws ``shape``."""
    pose = planar_pose(shape.x, shape.y, shape.z, shape.yaw)
    if shape.half is not None:
        hx, hy = shape.half
        size = {"x": 2 * hx, "y": 2 * hy, "z": shape.height}
        return "cubes", {"pose": pose, "size": size, "color": _color(shape)}
    diameter = 2 * (shape.radius or 0.0)
    cylinder: dict[str, Any] = {"pose": pose}
    cylinder["size"] = {"x": diameter, "y": diameter, "z": shape.height}
    cylinder.update(bottom_scale=1.0, top_scale=1.0, color=_color(shape))
    return "cylinders", cylinder


def scene_update(plan: Iterable[object], log_time: int) -> dict[str, Any]:
    """The ``foxglove.SceneUpdate`` that draws a floor ``plan`` in ``map``, for good.

    Each well-formed shape (`FloorShape.read_plan`) is an entity named after it
    (its ``kind`` in the entity's metadata), stamped ``log_time`` (ns since 1970).
    """
    entities = []
    for shape in FloorShape.read_plan(plan):
        entity: dict[str, Any] = {"timestamp": stamp(log_time), "frame_id": "map"}
        entity.update(
            id=shape.name,
            lifetime={"sec": 0, "nsec": 0},  # never expires
            frame_locked=False,
            metadata=[{"key": "kind", "value": shape.kind}],
        )
        entity.update({name: [] for name in _PRIMITIVES})
        kind, primitive = _primitive(shape)
        entity[kind] = [primitive]
        entities.append(entity)
    return {"deletions": [], "entities": entities}
