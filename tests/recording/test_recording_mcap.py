"""The MCAP recorder: Foxglove's channels, checked with the ``mcap`` reader and Foxglove's SDK.

The ``mcap`` package reads the files back record by record; Foxglove's own
Python SDK (``foxglove-sdk``) builds its well-known messages from what the
file holds, which fails on a field name or type that is not Foxglove's.
"""

from __future__ import annotations

import json
import logging
import math
import sys
from math import inf, nan
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from foxglove_scene import check_scene
from pyrobots_aio import CorruptRecordingError, RecordingError, Robot
from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    MemoryRecorder,
    load,
    render_timeline_html,
    summarize,
)
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.telemetry import SCHEMAS

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from conftest import Played
    from pyrobots_aio.recording import Recorder

    Scenario = Callable[[Recorder], Awaitable[Played]]

MISSING = (
    "McapRecorder needs the 'mcap' package, which is optional: install it with "
    'pip install -e ".[mcap]" from a checkout (or pip install mcap), or record with JsonlRecorder'
)
EVENT_TOPICS = {"/pyrobots/actions", "/pyrobots/resources", "/pyrobots/monitors"}


def _read(path: Path) -> tuple[dict[str, Any], dict[str, str], dict[str, Any], list[Any]]:
    """Schemas (name: encoding), channels (topic: schema), metadata, and (topic, message, time)."""
    from mcap.reader import make_reader  # the mcap extra; the test session installs it

    with path.open("rb") as file:
        reader = make_reader(file)
        summary = reader.get_summary()
        assert summary is not None
        schemas = {s.name: s.encoding for s in summary.schemas.values()}
        names = {s.id: s.name for s in summary.schemas.values()}
        channels = {c.topic: names[c.schema_id] for c in summary.channels.values()}
        assert {c.message_encoding for c in summary.channels.values()} == {"json"}
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        messages = [
            (c.topic, _strict_json(m.data), m.log_time) for _, c, m in reader.iter_messages()
        ]
    return schemas, channels, metadata, messages


def _strict_json(text: str | bytes) -> Any:
    """Parse as JSON proper: NaN and Infinity, which Foxglove refuses, raise."""

    def refuse(constant: str) -> object:
        raise ValueError(f"not JSON: {constant}")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_executive_events_are_on_json_schema_channels(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.mcap"
    await record_scenario(McapRecorder(path, state_keys=["bumper"]))
    memory = MemoryRecorder(state_keys=["bumper"])
    await record_scenario(memory)

    schemas, channels, metadata, messages = _read(path)
    assert schemas == dict.fromkeys(SCHEMAS, "jsonschema")
    assert channels == {
        "/pyrobots/actions": "pyrobots_aio.ExecEvent",
        "/pyrobots/resources": "pyrobots_aio.ExecEvent",
        "/pyrobots/monitors": "pyrobots_aio.ExecEvent",
        "/pyrobots/pose": "foxglove.PoseInFrame",
        "/tf": "foxglove.FrameTransforms",
        "/pyrobots/log": "foxglove.Log",
        "/pyrobots/state/bumper": "pyrobots_aio.StateSample",
    }
    assert json.loads(metadata["pyrobots_aio"]["robot"]) == "Robot"
    assert metadata["pyrobots_aio.end"] == {"end": "5.5", "events": "49"}
    events = [(m["kind"], m["action"], m["name"]) for t, m, _ in messages if t in EVENT_TOPICS]
    assert events == [(e.kind.value, e.action, e.name) for e in memory.events]
    topics = {topic for topic, message, _ in messages if message.get("kind") == "monitor.fired"}
    assert topics == {"/pyrobots/monitors"}
    samples = [(m["time"], m["value"]) for t, m, _ in messages if t == "/pyrobots/state/bumper"]
    assert samples == [(0.0, False), (3.0, True), (3.02, False)]
    logs = [m["message"] for t, m, _ in messages if t == "/pyrobots/log"]
    assert logs[:2] == ["monitor bumper becomes=True fired", "drive#5 preempted for 'wheels'"]
    assert "oops#7 failed: ValueError('boom')" in logs
    stamps = [stamp for _, _, stamp in messages]
    assert stamps == sorted(stamps)
    assert stamps[-1] - stamps[0] == 5_500_000_000  # loop seconds, in nanoseconds


async def _walk(*recorders: Recorder) -> None:
    robot = SimRobot(seed=3)
    for recorder in recorders:
        recorder.attach(robot)
    try:
        async with robot:
            await robot.undock()
            await robot.rotate_angle(math.pi / 2)
            await robot.drive_distance(0.3)
            logging.getLogger("pyrobots_aio.test").warning("checkpoint %d", 7)
            await robot.dock()
    finally:
        for recorder in recorders:
            recorder.close()


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_pose_frames_and_logs_use_foxglove_well_known_schemas(tmp_path: Path) -> None:
    from foxglove import messages as fox

    path = tmp_path / "walk.mcap"
    memory = MemoryRecorder()
    await _walk(McapRecorder(path, logs=True), memory)
    _, channels, _, messages = _read(path)
    recorded = memory.recording()

    def stamp(body: dict[str, int]) -> fox.Timestamp:
        return fox.Timestamp(sec=body["sec"], nsec=body["nsec"])

    poses = [m for t, m, _ in messages if t == "/pyrobots/pose"]
    transforms = [m for t, m, _ in messages if t == "/tf"]
    logs = [m for t, m, _ in messages if t == "/pyrobots/log"]
    assert len(poses) == len(transforms) == len(recorded.poses) > 500
    for body in poses:  # Foxglove's SDK takes every field as it is: names and types
        pose = body["pose"]
        fox.PoseInFrame(
            timestamp=stamp(body["timestamp"]),
            frame_id=body["frame_id"],
            pose=fox.Pose(
                position=fox.Vector3(**pose["position"]),
                orientation=fox.Quaternion(**pose["orientation"]),
            ),
        ).encode()
    for body in transforms:
        fox.FrameTransforms(
            transforms=[
                fox.FrameTransform(
                    timestamp=stamp(t["timestamp"]),
                    parent_frame_id=t["parent_frame_id"],
                    child_frame_id=t["child_frame_id"],
                    translation=fox.Vector3(**t["translation"]),
                    rotation=fox.Quaternion(**t["rotation"]),
                )
                for t in body["transforms"]
            ]
        ).encode()
    levels = {2: fox.LogLevel.Info, 1: fox.LogLevel.Debug, 3: fox.LogLevel.Warning}
    for body in logs:
        fields = {k: v for k, v in body.items() if k not in {"timestamp", "level"}}
        fox.Log(timestamp=stamp(body["timestamp"]), level=levels[body["level"]], **fields).encode()
    assert {
        (t["parent_frame_id"], t["child_frame_id"]) for b in transforms for t in b["transforms"]
    } == {("map", "base_link")}
    assert {body["frame_id"] for body in poses} == {"map"}
    first, last = poses[0]["pose"], poses[-1]["pose"]
    assert (first["position"]["x"], first["position"]["y"]) == (
        recorded.poses.x[0],
        recorded.poses.y[0],
    )
    assert last["position"]["x"] == pytest.approx(recorded.poses.x[-1])
    (checkpoint,) = [b for b in logs if b["name"] == "pyrobots_aio.test"]
    assert (checkpoint["message"], checkpoint["level"]) == ("checkpoint 7", 3)
    assert (checkpoint["file"], checkpoint["line"] > 0) == (__file__, True)
    for name in ("PoseInFrame", "FrameTransforms", "Log"):  # Foxglove's names for them
        assert (
            channels[
                {"PoseInFrame": "/pyrobots/pose", "FrameTransforms": "/tf", "Log": "/pyrobots/log"}[
                    name
                ]
            ]
            == getattr(fox, name).get_schema().name
        )


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_arena_is_one_scene_update_at_the_start(tmp_path: Path) -> None:
    path = tmp_path / "walk.mcap"
    await _walk(McapRecorder(path))
    _, channels, _, messages = _read(path)
    assert channels["/pyrobots/arena"] == "foxglove.SceneUpdate"
    [(scene, stamp)] = [(m, s) for t, m, s in messages if t == "/pyrobots/arena"]
    assert stamp == min(s for _, _, s in messages)  # there from the first moment
    plan = list(load(path).header.floor_plan)
    assert {s["kind"] for s in plan} == {"wall", "obstacle", "dock"}
    assert {s["shape"] for s in plan} == {"box", "circle"}
    check_scene(scene, plan)
    walls = [e for e in scene["entities"] if e["id"].startswith("wall")]
    assert {(c["size"]["z"], c["pose"]["position"]["z"]) for e in walls for c in e["cubes"]} == {
        (0.3, 0.15)  # 30 cm high, standing on the floor
    }


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_robot_without_a_world_has_no_arena(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    robot = Robot()
    with McapRecorder(path).attach(robot):
        async with robot:
            await robot.sleep(0.5)
    _, channels, _, _ = _read(path)
    assert "/pyrobots/arena" not in channels


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_replay_gives_the_same_summary_and_page_for_mcap_and_json_lines(
    tmp_path: Path,
) -> None:
    await _walk(McapRecorder(tmp_path / "walk.mcap"), JsonlRecorder(tmp_path / "walk.jsonl"))
    mcap, jsonl = load(tmp_path / "walk.mcap"), load(tmp_path / "walk.jsonl")
    assert (mcap.complete, jsonl.complete) == (True, True)
    assert summarize(mcap) == summarize(jsonl)
    assert mcap.events == jsonl.events
    assert mcap.samples == jsonl.samples
    assert list(mcap.poses.times) == list(jsonl.poses.times)
    page = render_timeline_html(jsonl, title="walk")
    assert render_timeline_html(mcap, title="walk").replace(".mcap", ".jsonl") == page
    assert page.count('<polyline class="trail"') > 10


def test_without_the_mcap_extra_the_error_names_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "mcap.writer", None)  # as if mcap were not installed
    with pytest.raises(RecordingError) as info:
        McapRecorder(tmp_path / "run.mcap")
    assert str(info.value) == MISSING
    assert isinstance(info.value.__cause__, ImportError)
    assert not (tmp_path / "run.mcap").exists()


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_non_finite_floats_are_written_as_null(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    robot = Robot()
    with McapRecorder(path, state_keys=["range", "ranges"], metadata={"gain": nan}).attach(robot):
        async with robot:
            robot.state.update(range=nan, ranges=np.array([0.5, inf, -inf]))
            await robot.sleep(0.5)
            robot.state.range = 1.5
    _, _, metadata, messages = _read(path)
    assert [(topic, m["value"]) for topic, m, _ in messages] == [
        ("/pyrobots/state/range", None),
        ("/pyrobots/state/ranges", [0.5, None, None]),
        ("/pyrobots/state/range", 1.5),
    ]
    assert _strict_json(metadata["pyrobots_aio"]["metadata"]) == {"gain": None}


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_truncated_mcap_is_read_up_to_where_it_stops(tmp_path: Path) -> None:
    path = tmp_path / "walk.mcap"
    await _walk(McapRecorder(path))
    whole = load(path)
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    partial = load(cut, strict=False)
    assert partial.error is not None
    assert str(partial.error).startswith(f"{cut}:")
    assert (partial.end, partial.complete) == (None, False)
    assert 0 < len(partial.poses) < len(whole.poses)
    with pytest.raises(RecordingError):
        load(cut)


def test_a_valid_mcap_that_is_not_a_recording_is_refused(tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "other.mcap"
    with path.open("wb") as file:
        writer = Writer(file)
        writer.start()
        writer.finish()  # no pyrobots_aio metadata, no messages: was AttributeError
    for strict in (True, False):
        with pytest.raises(CorruptRecordingError) as info:
            load(path, strict=strict)
        assert str(info.value) == (
            f"{path}:1: no pyrobots_aio metadata record: not a pyrobots_aio recording"
        )
