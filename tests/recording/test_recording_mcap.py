"""The MCAP recorder: strict JSON messages on JSON-schema channels (Foxglove), its missing extra."""

from __future__ import annotations

import json
import sys
from math import inf, nan
from typing import TYPE_CHECKING

import numpy as np
import pytest

from pyrobots_aio import RecordingError, Robot
from pyrobots_aio.recording import McapRecorder, MemoryRecorder, load

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from conftest import Played
    from pyrobots_aio.recording import Recorder

    Scenario = Callable[[Recorder], Awaitable[Played]]

MISSING = (
    "McapRecorder needs the 'mcap' package, which is optional: install it with "
    'pip install mcap (or pip install -e ".[mcap]" in a checkout), or record with JsonlRecorder'
)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_an_mcap_file_holds_every_event_on_json_schema_channels(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    from mcap.reader import make_reader  # the mcap extra; the test session installs it

    path = tmp_path / "run.mcap"
    await record_scenario(McapRecorder(path, state_keys=["bumper"]))
    memory = MemoryRecorder(state_keys=["bumper"])
    await record_scenario(memory)

    with path.open("rb") as file:
        reader = make_reader(file)
        summary = reader.get_summary()
        assert summary is not None
        schemas = {
            s.name: (s.encoding, json.loads(s.data)["type"]) for s in summary.schemas.values()
        }
        channels = {c.topic: c.message_encoding for c in summary.channels.values()}
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        messages = [(c.topic, json.loads(m.data), m.log_time) for _, c, m in reader.iter_messages()]

    assert schemas == {
        "pyrobots_aio.ExecEvent": ("jsonschema", "object"),
        "pyrobots_aio.StateSample": ("jsonschema", "object"),
    }
    assert channels == {
        "/pyrobots/state/bumper": "json",
        "/pyrobots/actions": "json",
        "/pyrobots/resources": "json",
        "/pyrobots/monitors": "json",
    }
    assert json.loads(metadata["pyrobots_aio"]["robot"]) == "Robot"
    assert metadata["pyrobots_aio.end"] == {"end": "5.5", "events": "49"}
    assert len(messages) == len(memory.events) == 49
    expected = [(e.kind.value, e.action, e.name) for e in memory.events]
    assert [
        (m.get("kind", "state.sample"), m.get("action"), m.get("name", m.get("key")))
        for _, m, _ in messages
    ] == expected
    topics = {topic for topic, message, _ in messages if message.get("kind") == "monitor.fired"}
    assert topics == {"/pyrobots/monitors"}
    stamps = [stamp for _, _, stamp in messages]
    assert stamps == sorted(stamps)
    assert stamps[-1] - stamps[0] == 5_500_000_000  # loop seconds, in nanoseconds


def test_without_the_mcap_extra_the_error_names_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "mcap.writer", None)  # as if mcap were not installed
    with pytest.raises(RecordingError) as info:
        McapRecorder(tmp_path / "run.mcap")
    assert str(info.value) == MISSING
    assert isinstance(info.value.__cause__, ImportError)
    assert not (tmp_path / "run.mcap").exists()


def _strict_json(text: str | bytes) -> object:
    """Parse as JSON proper: NaN and Infinity, which Foxglove refuses, raise."""

    def refuse(constant: str) -> object:
        raise ValueError(f"not JSON: {constant}")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_non_finite_floats_are_written_as_null(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    path = tmp_path / "run.mcap"
    robot = Robot()
    with McapRecorder(path, state_keys=["range", "ranges"], metadata={"gain": nan}).attach(robot):
        async with robot:
            robot.state.update(range=nan, ranges=np.array([0.5, inf, -inf]))
            await robot.sleep(0.5)
            robot.state.range = 1.5
    with path.open("rb") as file:
        reader = make_reader(file)
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        values = [
            (c.topic, _strict_json(m.data)["value"])  # type: ignore[index]
            for _, c, m in reader.iter_messages()
        ]
    assert values == [
        ("/pyrobots/state/range", None),
        ("/pyrobots/state/ranges", [0.5, None, None]),
        ("/pyrobots/state/range", 1.5),
    ]
    assert _strict_json(metadata["pyrobots_aio"]["metadata"]) == {"gain": None}


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_load_says_an_mcap_file_is_not_json_lines(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    robot = Robot()
    with McapRecorder(path).attach(robot):
        async with robot:
            await robot.sleep(0.5)
    with pytest.raises(RecordingError) as info:
        load(path)
    assert str(info.value) == (
        f"{path} is an MCAP file (McapRecorder: open it in Foxglove); pyrobots-aio replay "
        "and load() read JSON Lines recordings: record one with JsonlRecorder, or with "
        "pyrobots-aio demo random-walk --record PATH.jsonl"
    )
