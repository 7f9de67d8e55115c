"""Checking a ``foxglove.SceneUpdate`` (JSON) against the floor plan it draws (MCAP and live tests).

Foxglove's own SDK builds each entity from the decoded fields, which fails on a
field name or type that is not Foxglove's; then each entity is compared with
its floor-plan shape.
"""

from __future__ import annotations

import math
from typing import Any

import pytest


def _pose(fox: Any, body: dict[str, Any]) -> Any:
    return fox.Pose(
        position=fox.Vector3(**body["position"]), orientation=fox.Quaternion(**body["orientation"])
    )


def _sdk_entity(fox: Any, entity: dict[str, Any]) -> Any:
    """The entity rebuilt by Foxglove's SDK (which refuses a name or type not Foxglove's)."""
    cubes = [
        fox.CubePrimitive(
            pose=_pose(fox, c["pose"]), size=fox.Vector3(**c["size"]), color=fox.Color(**c["color"])
        )
        for c in entity["cubes"]
    ]
    cylinders = [
        fox.CylinderPrimitive(
            pose=_pose(fox, c["pose"]),
            size=fox.Vector3(**c["size"]),
            bottom_scale=c["bottom_scale"],
            top_scale=c["top_scale"],
            color=fox.Color(**c["color"]),
        )
        for c in entity["cylinders"]
    ]
    return fox.SceneEntity(
        timestamp=fox.Timestamp(**entity["timestamp"]),
        frame_id=entity["frame_id"],
        id=entity["id"],
        lifetime=fox.Duration(**entity["lifetime"]),
        frame_locked=entity["frame_locked"],
        metadata=[fox.KeyValuePair(**kv) for kv in entity["metadata"]],
        cubes=cubes,
        cylinders=cylinders,
    )


def check_scene(scene: dict[str, Any], plan: list[dict[str, Any]]) -> None:
    """Assert that ``scene`` draws each shape of ``plan`` where and as it is, and nothing else."""
    from foxglove import messages as fox

    fox.SceneUpdate(entities=[_sdk_entity(fox, e) for e in scene["entities"]]).encode()
    assert scene["deletions"] == []
    assert [e["id"] for e in scene["entities"]] == [s["name"] for s in plan]
    for entity, shape in zip(scene["entities"], plan, strict=True):
        assert (entity["frame_id"], entity["lifetime"]) == ("map", {"sec": 0, "nsec": 0})
        assert entity["metadata"] == [{"key": "kind", "value": shape["kind"]}]
        kind = "cubes" if shape["shape"] == "box" else "cylinders"
        assert {k for k, v in entity.items() if isinstance(v, list) and v} == {"metadata", kind}
        (primitive,) = entity[kind]
        position, turn = primitive["pose"]["position"], primitive["pose"]["orientation"]
        assert position == {"x": shape["x"], "y": shape["y"], "z": shape["z"]}
        assert 2 * math.atan2(turn["z"], turn["w"]) == pytest.approx(shape["yaw"])
        if kind == "cubes":
            width, depth = (2 * h for h in shape["half"])
        else:
            width = depth = 2 * shape["radius"]
            assert (primitive["bottom_scale"], primitive["top_scale"]) == (1.0, 1.0)
        assert primitive["size"] == {"x": width, "y": depth, "z": shape["height"]}
        assert list(primitive["color"].values()) == shape["rgba"]
