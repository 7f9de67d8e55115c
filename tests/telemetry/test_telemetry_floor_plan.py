"""A floor plan is read once (`FloorShape`), the same for Foxglove's 3D panel and the replay map."""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio.recording import load, render_timeline_html
from pyrobots_aio.telemetry import FloorShape, FoxgloveChannels

if TYPE_CHECKING:
    from pathlib import Path

BOX = {"name": "wall", "kind": "wall", "shape": "box", "x": 0, "y": 1, "half": [2, 0.05]}
CIRCLE = {"name": "post", "shape": "circle", "x": 1.5, "y": -0.5, "radius": 0.1}


@pytest.mark.parametrize(
    ("raw", "why"),
    [
        ({**BOX, "x": None}, "no x"),
        ({**BOX, "y": float("nan")}, "a NaN"),
        ({**BOX, "yaw": "north"}, "a yaw that is no number"),
        ({**BOX, "x": True}, "a bool is no number"),
        ({**BOX, "half": [2]}, "one half side"),
        ({**BOX, "half": [2, "wide"]}, "a half side that is no number"),
        ({**CIRCLE, "radius": -0.1}, "a negative radius"),
        ({**CIRCLE, "shape": None}, "no shape"),
        ({**CIRCLE, "shape": "triangle"}, "an unknown shape"),
        ("wall", "not an object"),
    ],
)
def test_a_malformed_shape_is_left_out(raw: object, why: str) -> None:
    assert FloorShape.read(raw) is None, why


def test_a_shape_reads_its_numbers_and_defaults() -> None:
    assert FloorShape.read_plan([BOX, {**CIRCLE, "name": None, "rgba": [1, 0, "red", 1]}]) == [
        FloorShape("wall", "wall", 0.0, 1.0, 0.0, (2.0, 0.05), None, None, 0.1, 0.05),
        FloorShape("None", "obstacle", 1.5, -0.5, 0.0, None, 0.1, None, 0.1, 0.05),
    ]
    raw = {**CIRCLE, "yaw": 1, "height": 0.4, "z": 1, "rgba": [0, 0.5, 1, 1]}
    del raw["name"]
    assert FloorShape.read(raw, 7) == FloorShape(
        "shape7", "obstacle", 1.5, -0.5, 1.0, None, 0.1, (0.0, 0.5, 1.0, 1.0), 0.4, 1.0
    )


def test_a_shape_is_a_box_or_a_circle() -> None:
    with pytest.raises(
        ValueError, match=r"^a floor shape is a box or a circle, got half=\(1.0, 1.0\)"
    ):
        FloorShape("x", "obstacle", 0.0, 0.0, 0.0, (1.0, 1.0), 1.0, None, 0.1, 0.05)


def test_foxglove_and_the_replay_map_draw_the_same_shapes(tmp_path: Path) -> None:
    plan: list[Any] = [
        BOX,
        {**BOX, "name": "nowhere", "x": "far"},
        CIRCLE,
        {**CIRCLE, "name": "shapeless", "shape": None},
        {**BOX, "name": "tinted", "rgba": [0.5, 0.5, 0.5, "opaque"]},
    ]
    drawn = [shape.name for shape in FloorShape.read_plan(plan)]
    assert drawn == ["wall", "post", "tinted"]
    scene = json.loads(FoxgloveChannels(0, 0.0).arena(plan).data)
    assert [entity["id"] for entity in scene["entities"]] == drawn
    path = tmp_path / "plan.jsonl"
    header = {"format": "pyrobots_aio.recording", "version": 1, "t0": 0.0, "floor_plan": plan}
    path.write_text(json.dumps(header) + "\n" + json.dumps({"end": 1.0, "events": 0}) + "\n")
    page = render_timeline_html(load(path))
    shapes = re.findall(r'<(?:polygon|circle) class="shape [^>]*><title>(\w+) ', page)
    assert shapes == drawn
    assert "style=" not in "".join(re.findall(r'<(?:polygon|circle) class="shape [^>]*>', page))
