"""Truncated and corrupt recordings: the error names the line; what comes before is used."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import CorruptRecordingError, RecordingError, Robot, action
from pyrobots_aio.recording import JsonlRecorder, load, summarize

if TYPE_CHECKING:
    from pathlib import Path


@action
async def nap(robot: Robot) -> None:
    await asyncio.sleep(0)


def _record(path: Path, naps: int = 3) -> list[str]:
    """Record ``naps`` actions (3 events each); return the file's lines."""

    async def main() -> None:
        robot = Robot()
        with JsonlRecorder(path).attach(robot):
            async with robot:
                for _ in range(naps):
                    await nap(robot)

    asyncio.run(main())
    return path.read_text().splitlines(keepends=True)


def _expect(path: Path, line: int, problem: str) -> CorruptRecordingError:
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert (info.value.path, info.value.line) == (str(path), line)
    assert str(info.value) == f"{path}:{line}: {problem}"
    return info.value


def test_a_truncated_last_line_is_named_and_the_rest_still_read(tmp_path: Path) -> None:
    path = tmp_path / "crashed.jsonl"
    lines = _record(path)  # header, 9 events, end
    path.write_text("".join(lines[:8]) + lines[8][:25])  # the process died mid-write
    problem = "truncated line: it ends before its JSON object does (was the recorder closed?)"
    _expect(path, 9, problem)

    recording = load(path, strict=False)
    assert recording.error is not None
    assert (recording.error.line, str(recording.error)) == (9, f"{path}:9: {problem}")
    assert len(recording.events) == 7
    assert (recording.end, recording.complete) == (None, False)
    summary = summarize(recording)
    assert (summary.actions, summary.outcomes.succeeded, summary.outcomes.not_done) == (3, 2, 1)
    assert summary.complete is False


def test_a_recording_cut_between_lines_is_incomplete_but_not_corrupt(tmp_path: Path) -> None:
    path = tmp_path / "running.jsonl"
    lines = _record(path)
    path.write_text("".join(lines[:-1]))  # no end record: not closed (yet)
    recording = load(path)
    assert (len(recording.events), recording.error, recording.complete) == (9, None, False)


@pytest.mark.parametrize(
    ("bad", "problem"),
    [
        (
            "{oops}\n",
            "not valid JSON: Expecting property name enclosed in double quotes at column 2",
        ),
        ("[1, 2]\n", "expected a JSON object, got list"),
        ('{"t": 1.0}\n', "unknown event kind None; known kinds: "),
        (
            '{"t": "soon", "kind": "action.started"}\n',
            "'t' must be a number (the loop time), got 'soon'",
        ),
        (
            '{"t": 1.0, "kind": "action.started", "action": "one"}\n',
            "'action' must be int or null, got 'one'",
        ),
        (
            '{"t": 1.0, "kind": "action.started", "data": [1]}\n',
            "'data' must be an object, got [1]",
        ),
        ('{"end": 3.0, "events": 2}\n', "end record counts 2 records but 4 were read before it"),
        (b"\xff\xfe\n", "not UTF-8 text (byte 1 of the line)"),
    ],
)
def test_a_corrupt_line_in_the_middle_is_named(
    tmp_path: Path, bad: str | bytes, problem: str
) -> None:
    path = tmp_path / "corrupt.jsonl"
    lines = [line.encode() for line in _record(path)]
    path.write_bytes(
        b"".join([*lines[:5], bad if isinstance(bad, bytes) else bad.encode(), *lines[5:]])
    )
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert info.value.line == 6
    assert str(info.value).startswith(f"{path}:6: {problem}")
    recording = load(path, strict=False)
    assert len(recording.events) == 4
    assert recording.error is not None
    assert recording.error.line == 6


def test_data_after_the_end_record_is_corrupt(tmp_path: Path) -> None:
    path = tmp_path / "twice.jsonl"
    lines = _record(path, naps=1)
    path.write_text("".join(lines + lines[1:2]))
    _expect(path, 6, "data after the end record of line 5")


def test_blank_lines_are_ignored(tmp_path: Path) -> None:
    path = tmp_path / "blank.jsonl"
    lines = _record(path, naps=1)
    path.write_text("\n".join(lines))
    assert load(path).complete


def test_what_is_not_a_recording_is_refused_whatever_the_mode(tmp_path: Path) -> None:
    path = tmp_path / "other.jsonl"
    path.write_text('{"hello": "world"}\n')
    problem = (
        "not a pyrobots_aio recording: the first line has no \"format\": 'pyrobots_aio.recording'"
    )
    _expect(path, 1, problem)
    with pytest.raises(CorruptRecordingError):
        load(path, strict=False)
    path.write_text("")
    _expect(path, 1, "empty file: a recording starts with a header line")
    path.write_text('{"format": "pyrobots_aio.recording", "version": 1, "seed": "x"}\n')
    _expect(path, 1, "bad header: 'seed' must be int or null, got 'x'")


def test_a_newer_format_asks_for_an_upgrade(tmp_path: Path) -> None:
    path = tmp_path / "future.jsonl"
    path.write_text('{"format": "pyrobots_aio.recording", "version": 3}\n')
    with pytest.raises(RecordingError) as info:
        load(path, strict=False)
    assert type(info.value) is RecordingError
    assert str(info.value) == (
        f"{path}: recorded in format version 3; this pyrobots_aio reads versions up to 2: "
        "upgrade pyrobots-aio to read it"
    )


def test_a_missing_file_raises_the_os_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        load(tmp_path / "nowhere.jsonl")
