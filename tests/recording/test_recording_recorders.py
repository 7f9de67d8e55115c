"""Recorder behaviour: attaching and closing, state sampling, buffered writes."""

from __future__ import annotations

import asyncio
import json
import logging
import math
import re
from typing import TYPE_CHECKING

import numpy as np
import pytest

from log_support import logged
from pyrobots_aio import RecordingError, Robot, action
from pyrobots_aio.recording import JsonlRecorder, MemoryRecorder, load

if TYPE_CHECKING:
    from pathlib import Path

    from pyrobots_aio.recording import Recording


@action
async def nap(robot: Robot, seconds: float) -> None:
    await robot.sleep(seconds)


def _samples(recording: Recording) -> list[tuple[float, str, object]]:
    """Every sample, by time then key."""
    found = [
        (round(t, 6), key, value)
        for key, series in recording.samples.items()
        for t, value in zip(series.times, series.values, strict=True)
    ]
    return sorted(found, key=lambda s: (s[0], s[1]))


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_numbers_are_rate_limited_and_discrete_values_never_missed() -> None:
    robot = Robot()
    robot.state.update(v=0.0, bumper=False)
    with MemoryRecorder(state_keys=["v", "bumper"], sample_rate=10).attach(robot) as recorder:
        async with robot:
            for tick in range(1, 11):  # 50 Hz writes of v, a one-tick bumper press at tick 3
                await robot.sleep(0.02)
                robot.state.update(v=tick / 10, bumper=tick == 3)
            await robot.sleep(0.02)
            robot.state.v = 1.0  # the same value again: not a new sample
    assert recorder.events == []  # samples are not executive events
    assert _samples(recorder.recording()) == [
        (0.0, "bumper", False),  # the values present at attach
        (0.0, "v", 0.0),
        (0.06, "bumper", True),
        (0.08, "bumper", False),
        (0.1, "v", 0.5),
        (0.2, "v", 1.0),
    ]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_without_a_sample_rate_every_change_is_recorded() -> None:
    robot = Robot()
    with MemoryRecorder(state_keys="v", sample_rate=None).attach(robot) as recorder:
        async with robot:
            for value in (0.1, 0.2, 0.2, 0.3):
                robot.state.v = value
                robot.state.w = value  # not sampled
    assert _samples(recorder.recording()) == [(0.0, "v", 0.1), (0.0, "v", 0.2), (0.0, "v", 0.3)]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_numpy_values_are_written_as_json(tmp_path: Path) -> None:
    path = tmp_path / "np.jsonl"
    robot = Robot()
    with JsonlRecorder(path, state_keys=["ranges", "speed", "tags"]).attach(robot):
        async with robot:
            robot.state.update(ranges=np.array([0.5, 1.0]), speed=np.float64(0.25), tags={"a"})
    values = {key: list(s.values) for key, s in load(path).samples.items()}
    assert values == {"ranges": [[0.5, 1.0]], "speed": [0.25], "tags": [["a"]]}


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_lines_are_strict_json_non_finite_floats_null(tmp_path: Path) -> None:
    def refuse(constant: str) -> object:
        raise ValueError(f"not JSON: {constant}")

    path = tmp_path / "nan.jsonl"
    robot = Robot()
    keys = ["range", "ranges", "pose"]
    with JsonlRecorder(path, state_keys=keys, metadata={"gain": math.nan}).attach(robot):
        async with robot:
            robot.state.update(range=math.nan, ranges=np.array([0.1 + 0.2, math.inf]))
            robot.state.pose = {"x": -math.inf, "y": (1e-300, math.nan)}
            await robot.sleep(0.5)
            robot.state.range = 1 / 3
    lines = path.read_text().splitlines()
    assert [json.loads(line, parse_constant=refuse) for line in lines]  # every line parses
    recording = load(path)
    assert recording.header.metadata == {"gain": None}
    assert [(key, value) for _, key, value in _samples(recording)] == [
        ("pose", {"x": None, "y": [1e-300, None]}),
        ("range", None),
        ("ranges", [0.1 + 0.2, None]),  # finite values come back exactly
        ("range", 1 / 3),
    ]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_sample_keeps_the_value_it_had_among_batched_action_events(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.jsonl"
    robot = Robot()
    seen = [1]
    with JsonlRecorder(path, state_keys=["seen"], sample_rate=None).attach(robot):
        async with robot:
            handle = nap(robot, 1.0)  # its events wait in the batch
            await robot.sleep(0.5)
            robot.state.seen = seen
            seen.append(2)  # changed in place: no new sample, and the recorded one stays [1]
            await handle
            robot.state.seen = [1, 2, 3]
    lines = [json.loads(line) for line in path.read_text().splitlines()[1:-1]]
    assert [(line.get("kind", "sample"), line["t"], line.get("state")) for line in lines] == [
        ("action.spawned", 0.0, None),
        ("action.started", 0.0, None),
        ("sample", 0.5, {"seen": [1]}),
        ("action.finished", 1.0, None),
        ("sample", 1.0, {"seen": [1, 2, 3]}),
    ]
    assert _samples(load(path)) == [(0.5, "seen", [1]), (1.0, "seen", [1, 2, 3])]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_buffered_events_reach_the_file_after_the_flush_interval(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    robot = Robot()
    with JsonlRecorder(path, flush_interval=0.5).attach(robot):
        async with robot:
            await nap(robot, 0.1)
            assert len(path.read_text().splitlines()) == 1  # the header only, so far
            await robot.sleep(0.5)
            lines = path.read_text().splitlines()
            assert [json.loads(line)["kind"] for line in lines[1:]] == [
                "action.spawned",
                "action.started",
                "action.finished",
            ]
    assert json.loads(path.read_text().splitlines()[-1]) == {"end": 0.6, "events": 3}


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_full_buffer_is_written_at_once(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    robot = Robot()
    with JsonlRecorder(path, buffer_size=4).attach(robot):
        async with robot:
            await nap(robot, 0.1)
            assert len(path.read_text().splitlines()) == 1
            await nap(robot, 0.1)  # the 4th event fills the buffer
            assert len(path.read_text().splitlines()) == 5
    assert len(path.read_text().splitlines()) == 8


def test_attached_outside_a_loop_the_first_event_is_the_origin(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    robot = Robot()
    recorder = JsonlRecorder(path).attach(robot)

    async def main() -> float:
        async with robot:
            await nap(robot, 0.01)
            return robot.time()

    with recorder:
        stopped = asyncio.run(main())
    recording = load(path)
    assert recording.header.t0 is None
    assert recording.start == recording.events[0].time
    assert recording.end is not None
    assert recording.events[-1].time <= recording.end <= stopped + 0.5


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_recorder_passed_as_an_instrument_is_closed_by_its_owner(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    recorder = JsonlRecorder(path)
    async with Robot(instruments=[recorder]) as robot:
        await nap(robot, 1.0)
    recorder.close()
    recording = load(path)
    assert (recording.header.robot, recording.header.t0) == (None, 0.0)
    assert [e.kind.value for e in recording.events] == [
        "action.spawned",
        "action.started",
        "action.finished",
    ]
    assert recording.end == 1.0


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_events_after_close_are_dropped_with_one_warning(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = tmp_path / "run.jsonl"
    recorder = JsonlRecorder(path)
    async with Robot(instruments=[recorder]) as robot:
        await nap(robot, 0.1)
        recorder.close()
        recorder.close()  # closing twice does nothing
        await nap(robot, 0.1)
        await nap(robot, 0.1)
    assert recorder.closed
    assert len(load(path).events) == 3
    warnings = [r.getMessage() for r in logged(caplog) if r.levelno == logging.WARNING]
    assert warnings == [f"{recorder!r} is closed; events are no longer recorded"]


def test_a_recorder_records_one_robot_once() -> None:
    robot, other = Robot(), Robot()
    recorder = MemoryRecorder().attach(robot)
    with pytest.raises(RecordingError) as info:
        recorder.attach(other)
    assert str(info.value) == (
        f"MemoryRecorder is attached to {robot!r}; create a new recorder for {other!r}"
    )
    recorder.close()
    assert list(robot.instruments) == []
    with pytest.raises(RecordingError) as info:
        recorder.attach(robot)
    assert str(info.value) == f"MemoryRecorder is closed; create a new recorder for {robot!r}"


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            {"sample_rate": 0},
            "sample_rate must be a positive number of samples per second or None, got 0",
        ),
        ({"buffer_size": 0}, "buffer_size must be a positive number of events, got 0"),
        (
            {"flush_interval": -1.0},
            "flush_interval must be a positive number of seconds, got -1.0",
        ),
    ],
)
def test_bad_options_are_refused(tmp_path: Path, options: dict[str, float], message: str) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        JsonlRecorder(tmp_path / "x.jsonl", **options)  # type: ignore[arg-type]
    assert not (tmp_path / "x.jsonl").exists()
