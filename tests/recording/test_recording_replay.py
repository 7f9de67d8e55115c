"""Record the scenario of conftest.py, read it back, check every number of the summary."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EventKind
from pyrobots_aio.recording import (
    FORMAT,
    VERSION,
    ActionStats,
    Cancellation,
    Failure,
    JsonlRecorder,
    MemoryRecorder,
    Outcomes,
    ResourceStats,
    format_summary,
    load,
    summarize,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from conftest import Played
    from pyrobots_aio.recording import Recorder

    Scenario = Callable[[Recorder], Awaitable[Played]]

pytestmark = [pytest.mark.virtual_time, pytest.mark.asyncio]

PREEMPTED = "preempted by reflex#6 (priority 5) for 'wheels'"


async def test_the_summary_counts_what_the_scenario_did(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.jsonl"
    played = await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    recording = load(path)
    summary = summarize(recording)

    assert (recording.start, recording.end, recording.complete) == (0.0, 5.5, True)
    assert (summary.robot, summary.seed, summary.duration, summary.complete) == (
        "Robot",
        None,
        5.5,
        True,
    )
    assert (summary.records, summary.state_samples, summary.poses) == (46, 3, 0)
    assert summary.actions == 9
    assert summary.outcomes == Outcomes(succeeded=5, failed=1, cancelled=2, skipped=1)
    assert summary.actions_per_minute == (9,)
    assert summary.mean_actions_per_minute == pytest.approx(9 * 60 / 5.5)
    assert summary.events_per_minute == (1,)
    assert summary.mean_events_per_minute == pytest.approx(60 / 5.5)
    assert (summary.peak_concurrency, summary.peak_time) == (4, pytest.approx(0.1))
    assert summary.per_action == (
        ActionStats("drive", 4, Outcomes(succeeded=2, cancelled=2), 0.5, 1.5, 2.0),
        ActionStats("oops", 1, Outcomes(failed=1), 0.25, 0.25, 0.25),
        ActionStats("patrol", 1, Outcomes(succeeded=1), 5.0, 5.0, 5.0),
        ActionStats("reflex", 1, Outcomes(succeeded=1), 1.0, 1.0, 1.0),
        ActionStats("wave", 2, Outcomes(succeeded=1, skipped=1), 0.0, 0.25, 0.5),
    )
    assert summary.resources == (
        ResourceStats("arm", 0.5, pytest.approx(0.5 / 5.5), 1, 0, 0.0, 0),  # type: ignore[arg-type]
        ResourceStats("wheels", 5.5, 1.0, 5, 2, 1.0, 1),
    )
    assert summary.cancellations == (
        Cancellation(3.0, 5, "drive", PREEMPTED, 6, "reflex#6", "wheels"),
        Cancellation(5.5, 9, "drive", "operator stop", None, None, None),
    )
    assert summary.failures == (Failure(3.25, 7, "oops", "ValueError('boom')"),)
    assert summary.monitor_firings == {played.monitor: 1}
    assert (summary.state_samples, summary.escalations, summary.abandoned) == (3, 0, 0)
    assert played.end == 5.5


async def test_a_cancellation_is_explained_by_the_recording(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path))
    events = load(path).events
    about_5 = [(e.kind, dict(e.data)) for e in events if e.action == 5]
    assert about_5 == [
        (EventKind.ACTION_SPAWNED, {"parent": 1}),
        (EventKind.ACTION_STARTED, {}),
        (
            EventKind.RESOURCE_ACQUIRED,
            {"resources": ["wheels"], "leaves": ["wheels"], "priority": 0},
        ),
        (
            EventKind.RESOURCE_PREEMPTED,
            {
                "resource": "wheels",
                "by": 6,
                "reason": PREEMPTED,
                "resources": ["wheels"],
                "leaves": ["wheels"],
                "priority": 0,
            },
        ),
        (EventKind.CANCEL_REQUESTED, {"reason": PREEMPTED, "by": 6}),
        (
            EventKind.RESOURCE_RELEASED,
            {"resources": ["wheels"], "leaves": ["wheels"], "priority": 0},
        ),
        (EventKind.ACTION_FINISHED, {"outcome": "cancelled", "error": None}),
    ]
    spawn_6 = next(e for e in events if e.action == 6)
    assert (spawn_6.kind, spawn_6.name, spawn_6.time) == (EventKind.ACTION_SPAWNED, "reflex", 3.0)
    fired = [e for e in events if e.kind is EventKind.MONITOR_FIRED]
    assert [(e.time, e.data["callback"]) for e in fired] == [(3.0, "started")]


async def test_the_file_is_one_json_object_per_line(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"], metadata={"run": 7}))
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    header, first, end = lines[0], lines[1], lines[-1]
    assert header["format"] == FORMAT
    assert header["version"] == VERSION
    keys = ("robot", "seed", "t0", "state_keys", "sample_rate", "pose_frame", "floor_plan")
    assert {k: header[k] for k in keys} == {
        "robot": "Robot",
        "seed": None,
        "t0": 0.0,
        "state_keys": ["bumper"],
        "sample_rate": None,
        "pose_frame": None,  # a plain Robot has no base_link frame
        "floor_plan": [],
    }
    assert header["metadata"] == {"run": 7}
    assert header["created"].endswith("+00:00")
    assert first == {"t": 0.0, "state": {"bumper": False}}
    assert end == {"end": 5.5, "events": 49}
    assert len(lines) == 51


async def test_the_memory_recorder_records_the_same_events(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    memory = MemoryRecorder(state_keys=["bumper"])
    await record_scenario(memory)
    from_file, in_memory = load(path), memory.recording()
    assert in_memory.start == 5.5  # the second run, on the same virtual clock
    assert (in_memory.end, in_memory.complete) == (11.0, True)
    assert [(e.kind, e.time, e.action, e.name, dict(e.data)) for e in from_file.events] == [
        (e.kind, round(e.time - 5.5, 9), e.action, e.name, dict(e.data)) for e in in_memory.events
    ]
    assert format_summary(summarize(in_memory)) == format_summary(summarize(from_file))


async def test_the_summary_reads_as_a_table(tmp_path: Path, record_scenario: Scenario) -> None:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    text = format_summary(summarize(load(path)))
    assert text.splitlines()[:5] == [
        "Robot: 5.500 s recorded, 46 events (3 state samples, 0 poses), closed cleanly",
        "  actions            9: 5 succeeded, 1 failed, 2 cancelled, 1 skipped, 0 not done",
        "  actions per minute 98.2 mean; by minute: 9",
        "  events per minute  10.9 mean (monitor firings); by minute: 1",
        "  peak concurrency   4 actions at 0.100 s",
    ]
    assert "  action  count  ok  failed  cancelled  skipped  min s  median s  max s" in text
    assert "  drive       4   2       0          2        0  0.500     1.500  2.000" in text
    assert "  wheels     5.500  100.0%         5      2       1.000          1" in text
    assert f"        3.000 s  drive#5 cancelled by reflex#6: {PREEMPTED}" in text
    assert "        5.500 s  drive#9 cancelled: operator stop" in text
    assert "        3.250 s  oops#7: ValueError('boom')" in text
