"""A sink of one's own (issue 24): written against the public API only, it sees typed events."""

from __future__ import annotations

import dataclasses
import re
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import (
    ActionFinished,
    ActionSpawned,
    ExecEvent,
    MonitorFired,
    ResourcePreempted,
    Robot,
    action,
)
from pyrobots_aio.recording import (
    JsonlRecorder,
    Recorder,
    RecordingHeader,
    RecordingOptions,
    load,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Mapping
    from pathlib import Path

    from conftest import Played

    Scenario = Callable[[Recorder[Any]], Awaitable[Played]]


class ListSink:
    """Keeps what it is given, and the order of the calls."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.header: RecordingHeader | None = None
        self.events: list[ExecEvent] = []
        self.samples: list[tuple[float, dict[str, object]]] = []
        self.end: float | None = None

    def open(self, header: RecordingHeader) -> None:
        self.calls.append("open")
        self.header = header

    def write_event(self, event: ExecEvent) -> None:
        self.calls.append("event")
        self.events.append(event)

    def write_samples(
        self, time: float, values: Mapping[str, object], pose: tuple[float, float, float] | None
    ) -> None:
        self.calls.append("samples")
        self.samples.append((time, dict(values)))

    def flush(self) -> None:
        self.calls.append("flush")

    def close(self, end: float | None) -> None:
        self.calls.append("close")
        self.end = end


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_list_sink_records_the_scenario_as_typed_events(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    sink = ListSink()
    options = RecordingOptions(state_keys=["bumper"], metadata={"by": "a list"})
    recorder = Recorder(sink, options)
    played = await record_scenario(recorder)
    assert recorder.sink is sink
    assert (sink.calls[0], sink.calls[-1], sink.calls.count("open")) == ("open", "close", 1)
    assert sink.header is not None
    assert (sink.header.robot, sink.header.state_keys, sink.header.t0) == (
        "Robot",
        ("bumper",),
        5.5,
    )
    assert sink.header.metadata == {"by": "a list"}
    assert sink.end == played.end
    assert [(round(t - 5.5, 9), values) for t, values in sink.samples] == [
        (0.0, {"bumper": False}),
        (3.0, {"bumper": True}),
        (3.02, {"bumper": False}),
    ]
    failed = [e for e in sink.events if isinstance(e, ActionFinished) and e.outcome == "failed"]
    assert [(e.name, e.error) for e in failed] == [("oops", "ValueError('boom')")]
    (preempted,) = [e for e in sink.events if isinstance(e, ResourcePreempted)]
    assert (preempted.action, preempted.by, preempted.resource, preempted.leaves) == (
        5,
        6,
        "wheels",
        ("wheels",),
    )
    (fired,) = [e for e in sink.events if isinstance(e, MonitorFired)]
    assert (fired.name, fired.value, fired.callback) == (played.monitor, True, "started")
    # the same run, read back from the file: the same typed events
    shifted = [dataclasses.replace(e, time=round(e.time - 5.5, 9)) for e in sink.events]
    assert load(path).events == tuple(shifted)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_sink_gets_the_events_of_a_robot_it_is_an_instrument_of() -> None:
    @action
    async def hello(robot: Robot) -> None:
        await robot.sleep(0.5)

    sink = ListSink()
    recorder = Recorder(sink, RecordingOptions(state_keys=()))
    async with Robot(instruments=[recorder]) as robot:
        await hello(robot)
        recorder.flush()
        recorder.close()
        await hello(robot)  # after closing: dropped
    assert sink.calls == ["open", "event", "event", "event", "flush", "close"]
    spawned, *_, finished = sink.events
    assert spawned == ActionSpawned(0.0, 1, "hello", None)
    assert finished == ActionFinished(0.5, 1, "hello", "succeeded", None)
    assert (sink.header and sink.header.t0, sink.end) == (0.0, 0.5)


def test_recording_options_refuse_a_bad_sample_rate() -> None:
    message = "sample_rate must be a positive number of samples per second or None, got 0"
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        RecordingOptions(sample_rate=0)
    assert RecordingOptions(state_keys="v").state_keys == ("v",)
    assert RecordingOptions(sample_rate=50).period == pytest.approx(0.02, rel=1e-5)
