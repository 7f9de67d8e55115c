"""Recordings as values, and reading them back from JSON Lines (`load`).

The file format, one JSON object per line::

    {"format": "pyrobots_aio.recording", "version": 1, "created": ..., "robot": ..., ...}
    {"t": 0.0, "action": 1, "kind": "action.spawned", "name": "walk", "data": {"parent": null}}
    ...
    {"end": 12.5, "events": 1234}

``t`` is the robot's loop time (``robot.time()``; simulation time in lockstep).
The end record is written by ``close()``: a recording without it was not closed
(the program crashed or is still running).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pyrobots_aio import CorruptRecordingError, EventKind, ExecEvent, RecordingError

if TYPE_CHECKING:
    from collections.abc import Generator, Iterator, Mapping

FORMAT = "pyrobots_aio.recording"
"""The ``format`` field of a recording's header line."""
VERSION = 1
"""The format version this library writes and reads."""

_KINDS = {kind.value: kind for kind in EventKind}
MCAP_MAGIC = b"\x89MCAP0\r\n"
"""How an MCAP file starts (`McapRecorder` writes them)."""


class _Bad(Exception):
    """A problem with one line; `load` turns it into `CorruptRecordingError`."""


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _optional(obj: Mapping[str, Any], key: str, kind: type | tuple[type, ...]) -> Any:
    value = obj.get(key)
    if value is not None and (not isinstance(value, kind) or isinstance(value, bool)):
        raise _Bad(f"{key!r} must be {getattr(kind, '__name__', kind)} or null, got {value!r}")
    return value


@dataclass(frozen=True, slots=True)
class RecordingHeader:
    """The facts at the top of a recording.

    Attributes:
        version: The format version.
        created: When recording started (ISO 8601, UTC), for people.
        robot: The robot's class name, when the recorder was attached to it.
        seed: The robot's seed (`SimRobot`), if it has one.
        t0: The loop time recording started at (the origin of relative times).
        state_keys: The state keys sampled.
        sample_rate: Most samples per second and numeric key (None: every change).
        metadata: Free facts given to the recorder.
    """

    version: int = VERSION
    created: str | None = None
    robot: str | None = None
    seed: int | None = None
    t0: float | None = None
    state_keys: tuple[str, ...] = ()
    sample_rate: float | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_json(cls, obj: Mapping[str, Any]) -> RecordingHeader:
        """Read a header line's object.

        Raises:
            ValueError: A field has the wrong type.
        """
        try:
            keys = obj.get("state_keys") or []
            if not isinstance(keys, list) or not all(isinstance(k, str) for k in keys):
                raise _Bad(f"'state_keys' must be a list of strings, got {keys!r}")
            metadata = obj.get("metadata") or {}
            if not isinstance(metadata, dict):
                raise _Bad(f"'metadata' must be an object, got {metadata!r}")
            return cls(
                version=obj.get("version", VERSION),
                created=_optional(obj, "created", str),
                robot=_optional(obj, "robot", str),
                seed=_optional(obj, "seed", int),
                t0=_optional(obj, "t0", (int, float)),
                state_keys=tuple(keys),
                sample_rate=_optional(obj, "sample_rate", (int, float)),
                metadata=metadata,
            )
        except _Bad as bad:
            raise ValueError(str(bad)) from None


@dataclass(frozen=True, slots=True)
class Recording:
    """A recorded run: its header and its events, in the order they happened.

    Attributes:
        header: The header facts.
        events: Every event, times in loop time (``robot.time()``).
        end: The loop time the recorder was closed at; None if it never was
            (a crash, a recording still being written, or a corrupt file).
        path: The file it was read from, if any.
        error: With ``load(path, strict=False)``: the first bad line; ``events``
            then holds everything before it.
    """

    header: RecordingHeader
    events: tuple[ExecEvent, ...]
    end: float | None = None
    path: str | None = None
    error: CorruptRecordingError | None = None

    @property
    def start(self) -> float:
        """The loop time recording started at (the header's ``t0``, else the first event)."""
        if self.header.t0 is not None:
            return self.header.t0
        return self.events[0].time if self.events else 0.0

    @property
    def stop(self) -> float:
        """The loop time recording stopped at (its end record, else the last event)."""
        last = self.events[-1].time if self.events else self.start
        return max(last, self.end) if self.end is not None else last

    @property
    def duration(self) -> float:
        """Seconds between `start` and `stop`."""
        return max(0.0, self.stop - self.start)

    @property
    def complete(self) -> bool:
        """Whether the recording was closed properly and read without error."""
        return self.end is not None and self.error is None


def event_from_json(obj: object) -> ExecEvent:
    """Read one event line's object.

    Raises:
        ValueError: It is not a valid event; the message says what is wrong.
    """
    try:
        if not isinstance(obj, dict):
            raise _Bad(f"expected a JSON object, got {type(obj).__name__}")
        t = obj.get("t")
        if not isinstance(t, int | float) or isinstance(t, bool):
            raise _Bad(f"'t' must be a number (the loop time), got {t!r}")
        name_of_kind = obj.get("kind")
        kind = _KINDS.get(name_of_kind) if isinstance(name_of_kind, str) else None
        if kind is None:
            raise _Bad(f"unknown event kind {name_of_kind!r}; known kinds: {sorted(_KINDS)}")
        data = obj.get("data") or {}
        if not isinstance(data, dict):
            raise _Bad(f"'data' must be an object, got {data!r}")
        ident = _optional(obj, "action", int)
        name = _optional(obj, "name", str)
        return ExecEvent(kind, float(t), ident, name, data)
    except _Bad as bad:
        raise ValueError(str(bad)) from None


def _lines(path: str) -> Generator[tuple[int, str, bool], None, None]:
    """Each line's number, text, and whether it ended with a newline."""
    with open(path, "rb") as file:
        if file.read(len(MCAP_MAGIC)) == MCAP_MAGIC:
            msg = (
                f"{path} is an MCAP file (McapRecorder: open it in Foxglove); pyrobots-aio "
                "replay and load() read JSON Lines recordings: record one with JsonlRecorder, "
                "or with pyrobots-aio demo random-walk --record PATH.jsonl"
            )
            raise RecordingError(msg)
        file.seek(0)
        for number, raw in enumerate(file, start=1):
            try:
                text = raw.decode("utf-8")
            except UnicodeDecodeError as exc:
                msg = f"not UTF-8 text (byte {exc.start + 1} of the line)"
                raise CorruptRecordingError(path, number, msg) from None
            yield number, text, text.endswith("\n")


def _parse(path: str, number: int, text: str, complete: bool) -> Any:
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        if not complete:
            problem = (
                "truncated line: it ends before its JSON object does (was the recorder closed?)"
            )
        else:
            problem = f"not valid JSON: {exc.msg} at column {exc.colno}"
        raise CorruptRecordingError(path, number, problem) from None


def _header(path: str, lines: Iterator[tuple[int, str, bool]]) -> RecordingHeader:
    first = next(lines, None)
    if first is None:
        raise CorruptRecordingError(path, 1, "empty file: a recording starts with a header line")
    obj = _parse(path, *first)
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        problem = f'not a pyrobots_aio recording: the first line has no "format": {FORMAT!r}'
        raise CorruptRecordingError(path, 1, problem)
    version = obj.get("version")
    if not isinstance(version, int) or version > VERSION:
        msg = (
            f"{path}: recorded in format version {version!r}; this pyrobots_aio reads "
            f"version {VERSION}: upgrade pyrobots-aio to read it"
        )
        raise RecordingError(msg)
    try:
        return RecordingHeader.from_json(obj)
    except ValueError as exc:
        raise CorruptRecordingError(path, 1, f"bad header: {exc}") from None


def _end(obj: dict[str, Any], count: int) -> float | None:
    end, events = obj.get("end"), obj.get("events")
    if end is not None and not _number(end):
        raise _Bad(f"end record: 'end' must be a number or null, got {end!r}")
    if events != count:
        raise _Bad(f"end record counts {events!r} events but {count} were read before it")
    return None if end is None else float(end)


def _body(
    path: str, lines: Iterator[tuple[int, str, bool]]
) -> tuple[list[ExecEvent], float | None]:
    events: list[ExecEvent] = []
    end: float | None = None
    closed_at = 0
    try:
        for number, text, complete in lines:
            if not text.strip():
                continue
            if closed_at:
                problem = f"data after the end record of line {closed_at}"
                raise CorruptRecordingError(path, number, problem)
            obj = _parse(path, number, text, complete)
            try:
                if isinstance(obj, dict) and "end" in obj and "kind" not in obj:
                    end, closed_at = _end(obj, len(events)), number
                else:
                    events.append(event_from_json(obj))
            except (ValueError, _Bad) as exc:
                raise CorruptRecordingError(path, number, str(exc)) from None
    except CorruptRecordingError as error:
        raise _Partial(events, error) from None
    return events, end


class _Partial(Exception):
    """The events read before a corrupt line, and the error."""

    def __init__(self, events: list[ExecEvent], error: CorruptRecordingError) -> None:
        super().__init__(str(error))
        self.events = events
        self.error = error


def load(path: str | os.PathLike[str], *, strict: bool = True) -> Recording:
    """Read a JSON Lines recording written by `JsonlRecorder`.

    Args:
        path: The recording file.
        strict: If True, a corrupt or truncated line raises. If False, the
            recording of every line before it is returned, with the error in
            `Recording.error` (a header that cannot be read always raises).

    Raises:
        CorruptRecordingError: A line cannot be read; the error names the file
            and the 1-based line number (``.path``, ``.line``).
        RecordingError: The file was written by a newer format version, or is an
            MCAP file (`McapRecorder`), which this reader does not read.
        OSError: The file cannot be opened.

    Example:
        >>> recording = load("run.jsonl")  # doctest: +SKIP
        >>> recording.duration, len(recording.events)  # doctest: +SKIP
        (61.3, 2210)
    """
    name = os.fspath(path)
    lines = _lines(name)
    try:
        header = _header(name, lines)
        events, end = _body(name, lines)
    except _Partial as partial:
        if strict:
            raise partial.error from None
        return Recording(header, tuple(partial.events), None, name, partial.error)
    finally:
        lines.close()
    return Recording(header, tuple(events), end, name)
