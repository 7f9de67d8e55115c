"""Recordings as values, and reading them back (`load`: JSON Lines or MCAP).

The JSON Lines format (version 2), one JSON object per line::

    {"format": "pyrobots_aio.recording", "version": 2, "created": ..., "robot": ..., ...}
    {"t": 0.0, "action": 1, "kind": "action.spawned", "name": "walk", "data": {"parent": null}}
    {"t": 0.02, "state": {"v": 0.01, "bumper": false}, "pose": [-1.728, 0.0, 0.0]}
    ...
    {"end": 12.5, "events": 1234}

``t`` is the robot's loop time (``robot.time()``; simulation time in lockstep).
Executive events carry a ``kind``; their ``data`` is `ExecEvent.data`, read
back by `pyrobots_aio.event_from_data` (which reads older files too). A sample
line carries the state keys written at ``t`` whose values changed (``state``)
and the robot's pose in the ``map`` frame, ``[x, y, yaw]`` (``pose``, the
header's ``pose_frame`` seen from ``map``); a value holds until the key's next
sample. By default every change is recorded (each control tick, for a simulated
robot); with a ``sample_rate`` (header) numbers and the pose are downsampled to
at most that many samples a second, while booleans and other discrete values
are still recorded on every change. The header's ``floor_plan`` (a simulated
robot's arena: walls, obstacles, dock) lets replay draw the map without MuJoCo.
The end record, with the number of lines before it, is written by ``close()``:
a recording without it was not closed (the program crashed or is still
running). Version 1 files (state samples as ``state.sample`` events) are read
too.

Reading is safe on untrusted files: only a regular file is read (not a
FIFO, which would block, nor a device like ``/dev/zero``, which never ends),
a record (a line; an MCAP record) is at most `MAX_RECORD` bytes, numbers must
be finite (``NaN``, ``Infinity`` and ``1e400`` are refused), loop times within
`MAX_TIME` seconds of 0, nesting is bounded, and the memory used grows with
the number of records, not with the time span.
"""

from __future__ import annotations

import json
import math
import os
import reprlib
import stat
from array import array
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pyrobots_aio import (
    CorruptRecordingError,
    EventKind,
    ExecEvent,
    RecordingError,
    StateSampled,
    event_from_data,
)

if TYPE_CHECKING:
    from collections.abc import Generator, Iterator, Mapping, Sequence
    from typing import BinaryIO

FORMAT = "pyrobots_aio.recording"
"""The ``format`` field of a recording's header line."""
VERSION = 2
"""The format version this library writes (it reads every version up to this one)."""

_KINDS = {kind.value: kind for kind in EventKind}
MCAP_MAGIC = b"\x89MCAP0\r\n"
"""How an MCAP file starts (`McapRecorder` writes them)."""
_MAX_DIGITS = 40
"""Longest integer literal read: far beyond any count or time, far below float overflow."""
MAX_RECORD = 64 * 1024 * 1024
"""Longest record read, in bytes: a line of JSON Lines, an MCAP record (other than a chunk).

A recorded line holds one event or one sample of the state (kilobytes; a
camera image as a list of numbers, a few megabytes)."""
MAX_TIME = 1e18
"""Largest loop time read, in seconds either side of 0 (30 billion years): far beyond any
run, and far enough below float overflow that the span between two times is a number."""


class _Bad(Exception):
    """A problem with one line; `load` turns it into `CorruptRecordingError`."""


_BRIEF = reprlib.Repr()
_BRIEF.maxstring = _BRIEF.maxother = 80


def brief(value: object) -> str:
    """``repr(value)`` cut short (long strings, long or deep lists): errors stay one short line."""
    return _BRIEF.repr(value)


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def loop_time(value: object, name: str = "t") -> float:
    """``value`` as a loop time (a number within `MAX_TIME`); else `ValueError` naming ``name``."""
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise ValueError(f"{name!r} must be a number (the loop time), got {brief(value)}")
    if not -MAX_TIME <= value <= MAX_TIME:
        msg = f"{name!r} is out of range: {brief(value)} (loop times are within ±{MAX_TIME:g} s)"
        raise ValueError(msg)
    return float(value)


def _start(obj: Mapping[str, Any]) -> float | None:
    t0 = obj.get("t0")
    try:
        return None if t0 is None else loop_time(t0, "t0")
    except ValueError as exc:
        raise _Bad(str(exc)) from None


def _optional(obj: Mapping[str, Any], key: str, kind: type | tuple[type, ...]) -> Any:
    value = obj.get(key)
    if value is not None and (not isinstance(value, kind) or isinstance(value, bool)):
        raise _Bad(f"{key!r} must be {getattr(kind, '__name__', kind)} or null, got {brief(value)}")
    return value


@dataclass(frozen=True, slots=True)
class Series:
    """One state key's recorded values: each holds from its time until the next one.

    Attributes:
        key: The state key.
        times: Loop times of the samples, in order.
        values: The values (numbers, booleans, strings or JSON values).
    """

    key: str
    times: Sequence[float]
    values: Sequence[object]

    def __len__(self) -> int:
        return len(self.times)


@dataclass(frozen=True, slots=True)
class PoseTrack:
    """The robot's recorded pose in the ``map`` frame, over time.

    Attributes:
        frame: The frame whose pose this is (``base_link``).
        times: Loop times, in order.
        x: Metres, in ``map``.
        y: Metres, in ``map``.
        yaw: Radians, counter-clockwise from the ``map`` x axis.
    """

    frame: str = "base_link"
    times: Sequence[float] = ()
    x: Sequence[float] = ()
    y: Sequence[float] = ()
    yaw: Sequence[float] = ()

    def __len__(self) -> int:
        return len(self.times)


@dataclass(frozen=True, slots=True)
class RecordingHeader:
    """The facts at the top of a recording.

    Attributes:
        version: The format version.
        created: When recording started (ISO 8601, UTC), for people.
        robot: The robot's class name, when the recorder was attached to it.
        seed: The robot's seed (`SimRobot`), if it has one.
        t0: The loop time recording started at (the origin of relative times).
        state_keys: The state keys sampled; None: every key.
        sample_rate: Most samples per second of a number or the pose (None: every change).
        pose_frame: The frame whose pose in ``map`` is recorded, if any.
        floor_plan: The static shapes of the robot's world in the map plane
            (`pyrobots_aio.sim.SimWorld.floor_plan`), for drawing the map.
        metadata: Free facts given to the recorder.
    """

    version: int = VERSION
    created: str | None = None
    robot: str | None = None
    seed: int | None = None
    t0: float | None = None
    state_keys: tuple[str, ...] | None = ()
    sample_rate: float | None = None
    pose_frame: str | None = None
    floor_plan: tuple[Mapping[str, Any], ...] = ()
    metadata: Mapping[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The header line's object (with ``format``), as `from_json` reads it."""
        return {
            "format": FORMAT,
            "version": self.version,
            "created": self.created,
            "robot": self.robot,
            "seed": self.seed,
            "t0": self.t0,
            "state_keys": None if self.state_keys is None else list(self.state_keys),
            "sample_rate": self.sample_rate,
            "pose_frame": self.pose_frame,
            "floor_plan": list(self.floor_plan),
            "metadata": dict(self.metadata),
        }

    @classmethod
    def from_json(cls, obj: Mapping[str, Any]) -> RecordingHeader:
        """Read a header line's object.

        Raises:
            ValueError: A field has the wrong type.
        """
        try:
            keys = obj.get("state_keys", [])
            if keys is not None and (
                not isinstance(keys, list) or not all(isinstance(k, str) for k in keys)
            ):
                raise _Bad(f"'state_keys' must be a list of strings or null, got {brief(keys)}")
            metadata = obj.get("metadata") or {}
            if not isinstance(metadata, dict):
                raise _Bad(f"'metadata' must be an object, got {brief(metadata)}")
            plan = obj.get("floor_plan") or []
            if not isinstance(plan, list) or not all(isinstance(s, dict) for s in plan):
                raise _Bad(f"'floor_plan' must be a list of objects, got {brief(plan)}")
            return cls(
                version=obj.get("version", VERSION),
                created=_optional(obj, "created", str),
                robot=_optional(obj, "robot", str),
                seed=_optional(obj, "seed", int),
                t0=_start(obj),
                state_keys=None if keys is None else tuple(keys),
                sample_rate=_optional(obj, "sample_rate", (int, float)),
                pose_frame=_optional(obj, "pose_frame", str),
                floor_plan=tuple(plan),
                metadata=metadata,
            )
        except _Bad as bad:
            raise ValueError(str(bad)) from None


@dataclass(frozen=True, slots=True)
class Recording:
    """A recorded run: its header, its events in the order they happened, its samples.

    Attributes:
        header: The header facts.
        events: Every executive event, times in loop time (``robot.time()``).
        end: The loop time the recorder was closed at; None if it never was
            (a crash, a recording still being written, or a corrupt file).
        path: The file it was read from, if any.
        error: With ``load(path, strict=False)``: the first bad line; ``events``
            then holds everything before it.
        samples: The sampled state, one `Series` per key, keys sorted.
        poses: The robot's pose in ``map`` over time (empty if not recorded).
    """

    header: RecordingHeader
    events: tuple[ExecEvent, ...]
    end: float | None = None
    path: str | None = None
    error: CorruptRecordingError | None = None
    samples: Mapping[str, Series] = field(default_factory=dict)
    poses: PoseTrack = field(default_factory=PoseTrack)

    @property
    def start(self) -> float:
        """The loop time recording started at (the header's ``t0``, else the first record)."""
        if self.header.t0 is not None:
            return self.header.t0
        firsts = [self.events[0].time] if self.events else []
        firsts += [s.times[0] for s in self.samples.values() if len(s)]
        firsts += [self.poses.times[0]] if len(self.poses) else []
        return min(firsts, default=0.0)

    @property
    def stop(self) -> float:
        """The loop time recording stopped at (its end record, else the last record)."""
        lasts = [self.events[-1].time] if self.events else []
        lasts += [s.times[-1] for s in self.samples.values() if len(s)]
        lasts += [self.poses.times[-1]] if len(self.poses) else []
        last = max(lasts, default=self.start)
        return max(last, self.end) if self.end is not None else last

    @property
    def duration(self) -> float:
        """Seconds between `start` and `stop`."""
        return max(0.0, self.stop - self.start)

    @property
    def complete(self) -> bool:
        """Whether the recording was closed properly and read without error."""
        return self.end is not None and self.error is None

    @property
    def state_samples(self) -> int:
        """The number of state values recorded (every key)."""
        return sum(len(s) for s in self.samples.values())


class SeriesBuilder:
    """Gathers samples while a recording is read or recorded; `build` freezes them.

    Numbers are kept as C doubles (8 bytes each), so memory follows the number
    of samples and nothing else.
    """

    def __init__(self) -> None:
        self._times: dict[str, array[float]] = {}
        self._values: dict[str, list[object]] = {}
        self._pose: tuple[array[float], ...] = tuple(array("d") for _ in range(4))

    def add(self, time: float, key: str, value: object) -> None:
        """Add one sample of ``key``."""
        times = self._times.get(key)
        if times is None:
            times = self._times[key] = array("d")
            self._values[key] = []
        times.append(time)
        self._values[key].append(value)

    def add_pose(self, time: float, x: float, y: float, yaw: float) -> None:
        """Add one pose."""
        for column, value in zip(self._pose, (time, x, y, yaw), strict=True):
            column.append(value)

    def build(self, pose_frame: str | None) -> tuple[dict[str, Series], PoseTrack]:
        """The series (keys sorted) and the track of ``pose_frame``."""
        series = {}
        for key in sorted(self._times):
            values: Sequence[object] = self._values[key]
            if all(_number(v) for v in values):
                values = array("d", [float(v) for v in values])  # type: ignore[arg-type]
            series[key] = Series(key, self._times[key], values)
        times, x, y, yaw = self._pose
        return series, PoseTrack(pose_frame or "base_link", times, x, y, yaw)


def event_from_json(obj: object) -> ExecEvent:
    """Read one event line's object.

    Raises:
        ValueError: It is not a valid event; the message says what is wrong.
    """
    try:
        if not isinstance(obj, dict):
            raise _Bad(f"expected a JSON object, got {type(obj).__name__}")
        t = _time(obj)
        name_of_kind = obj.get("kind")
        kind = _KINDS.get(name_of_kind) if isinstance(name_of_kind, str) else None
        if kind is None:
            raise _Bad(f"unknown event kind {brief(name_of_kind)}; known kinds: {sorted(_KINDS)}")
        data = obj.get("data") or {}
        if not isinstance(data, dict):
            raise _Bad(f"'data' must be an object, got {brief(data)}")
        ident = _optional(obj, "action", int)
        name = _optional(obj, "name", str)
        return event_from_data(kind, t, ident, name, data)
    except _Bad as bad:
        raise ValueError(str(bad)) from None


def _time(obj: Mapping[str, Any]) -> float:
    try:
        return loop_time(obj.get("t"))
    except ValueError as exc:
        raise _Bad(str(exc)) from None


def _pose(value: object) -> tuple[float, float, float]:
    if not (isinstance(value, list) and len(value) == 3 and all(_number(v) for v in value)):
        raise _Bad(f"'pose' must be [x, y, yaw] numbers, got {brief(value)}")
    return float(value[0]), float(value[1]), float(value[2])


def _refuse_constant(name: str) -> Any:
    raise _Bad(f"{name} is not a number a recording may hold (only finite numbers)")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _Bad(f"the number {text[:40]} is out of range (only finite numbers)")
    return value


def _bounded_int(text: str) -> int:
    if len(text) > _MAX_DIGITS:
        raise _Bad(f"an integer of {len(text)} digits is out of range")
    return int(text)


_DECODER = json.JSONDecoder(
    parse_float=_finite_float, parse_int=_bounded_int, parse_constant=_refuse_constant
)


def parse_json(text: str | bytes) -> Any:
    """Strict JSON: finite numbers only, bounded nesting.

    Raises:
        ValueError: Not such JSON; the message says why (ready for a user).
    """
    try:
        return _DECODER.decode(text.decode("utf-8") if isinstance(text, bytes) else text)
    except _Bad as bad:
        raise ValueError(str(bad)) from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"not valid JSON: {exc.msg} at column {exc.colno}") from None
    except RecursionError:
        raise ValueError("not valid JSON: nested too deeply") from None


def _lines(path: str, file: BinaryIO) -> Generator[tuple[int, str, bool], None, None]:
    """Each line's number, text, and whether it ended with a newline."""
    number = 0
    while raw := file.readline(MAX_RECORD + 1):
        number += 1
        if len(raw) > MAX_RECORD and not raw.endswith(b"\n"):
            msg = f"a line longer than {MAX_RECORD} bytes (the most read): not a recording?"
            raise CorruptRecordingError(path, number, msg)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            msg = f"not UTF-8 text (byte {exc.start + 1} of the line)"
            raise CorruptRecordingError(path, number, msg) from None
        yield number, text, text.endswith("\n")


def _parse(path: str, number: int, text: str, complete: bool) -> Any:
    try:
        return parse_json(text)
    except ValueError as exc:
        if not complete and str(exc).startswith("not valid JSON"):
            problem = (
                "truncated line: it ends before its JSON object does (was the recorder closed?)"
            )
        else:
            problem = str(exc)
        raise CorruptRecordingError(path, number, problem) from None


def read_header(path: str, obj: object, line: int = 1) -> RecordingHeader:
    """The header of a recording from its header object.

    Raises:
        CorruptRecordingError: It is not a pyrobots_aio header, or a field is wrong.
        RecordingError: It was written by a newer format version.
    """
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        problem = f'not a pyrobots_aio recording: the first line has no "format": {FORMAT!r}'
        raise CorruptRecordingError(path, line, problem)
    version = obj.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version > VERSION:
        msg = (
            f"{path}: recorded in format version {brief(version)}; this pyrobots_aio reads "
            f"versions up to {VERSION}: upgrade pyrobots-aio to read it"
        )
        raise RecordingError(msg)
    try:
        return RecordingHeader.from_json(obj)
    except ValueError as exc:
        raise CorruptRecordingError(path, line, f"bad header: {exc}") from None


def _header(path: str, lines: Iterator[tuple[int, str, bool]]) -> RecordingHeader:
    first = next(lines, None)
    if first is None:
        raise CorruptRecordingError(path, 1, "empty file: a recording starts with a header line")
    return read_header(path, _parse(path, *first))


def _end(obj: dict[str, Any], count: int) -> float | None:
    end, events = obj.get("end"), obj.get("events")
    if end is not None and not _number(end):
        raise _Bad(f"end record: 'end' must be a number or null, got {brief(end)}")
    if events != count:
        raise _Bad(f"end record counts {brief(events)} records but {count} were read before it")
    return None if end is None else loop_time(end, "end")


@dataclass
class _Body:
    """What the lines after the header hold, as they are read."""

    samples: SeriesBuilder
    events: list[ExecEvent] = field(default_factory=list)
    end: float | None = None
    records: int = 0

    def take(self, obj: object) -> None:
        """One record (event, sample line or v1 state sample)."""
        if not isinstance(obj, dict):
            raise _Bad(f"expected a JSON object, got {type(obj).__name__}")
        if "kind" not in obj and ("state" in obj or "pose" in obj):
            self._sample(obj)
        else:
            event = event_from_json(obj)
            if isinstance(event, StateSampled):  # version 1
                self.samples.add(event.time, event.name or "?", event.value)
            else:
                self.events.append(event)
        self.records += 1

    def _sample(self, obj: dict[str, Any]) -> None:
        t = _time(obj)
        state = obj.get("state") or {}
        if not isinstance(state, dict):
            raise _Bad(f"'state' must be an object, got {brief(state)}")
        pose = obj.get("pose")
        if pose is not None:
            self.samples.add_pose(t, *_pose(pose))
        for key, value in state.items():
            self.samples.add(t, key, value)


def _body(path: str, lines: Iterator[tuple[int, str, bool]], body: _Body) -> None:
    closed_at = 0
    for number, text, complete in lines:
        if not text.strip():
            continue
        if closed_at:
            problem = f"data after the end record of line {closed_at}"
            raise CorruptRecordingError(path, number, problem)
        obj = _parse(path, number, text, complete)
        try:
            if isinstance(obj, dict) and "end" in obj and "kind" not in obj:
                body.end, closed_at = _end(obj, body.records), number
            else:
                body.take(obj)
        except (ValueError, _Bad) as exc:
            raise CorruptRecordingError(path, number, str(exc)) from None


_KINDS_OF_FILE = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)
_NONBLOCK = getattr(os, "O_NONBLOCK", 0)


def _open_regular(path: str) -> BinaryIO:
    """``path`` opened for reading, if it is a regular file.

    It is opened without blocking (a FIFO would block the opening until a
    writer comes) and refused unless it is a regular file: a FIFO or a device
    (``/dev/zero``) can be endless.

    Raises:
        RecordingError: It is not a regular file.
        OSError: It cannot be opened.
    """
    fd = os.open(path, os.O_RDONLY | _NONBLOCK)
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = next((name for test, name in _KINDS_OF_FILE if test(mode)), "something else")
            msg = f"{path}: not a regular file but {kind}: a recording is a file"
            raise RecordingError(msg)
        if _NONBLOCK:
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def load(path: str | os.PathLike[str], *, strict: bool = True) -> Recording:
    """Read a recording written by `JsonlRecorder` or `McapRecorder` (the file tells which).

    Args:
        path: The recording file (JSON Lines, or MCAP with the ``mcap`` extra).
        strict: If True, a corrupt or truncated line raises. If False, the
            recording of every line before it is returned, with the error in
            `Recording.error` (a header that cannot be read always raises).

    Raises:
        CorruptRecordingError: A line cannot be read; the error names the file
            and the 1-based line number (``.path``, ``.line``; for MCAP, the
            message's position).
        RecordingError: The file was written by a newer format version, or is
            MCAP and the ``mcap`` package is missing, or is not a regular file
            (a FIFO, a device).
        OSError: The file cannot be opened.

    Examples:
        >>> recording = load("run.jsonl")  # doctest: +SKIP
        >>> recording.duration, len(recording.events)  # doctest: +SKIP
        (61.3, 2210)
    """
    name = os.fspath(path)
    with _open_regular(name) as file:
        if file.read(len(MCAP_MAGIC)) == MCAP_MAGIC:
            from ._mcap_read import load_mcap

            return load_mcap(name, file, strict=strict)
        file.seek(0)
        return _load_lines(name, file, strict=strict)


def _load_lines(name: str, file: BinaryIO, *, strict: bool) -> Recording:
    lines = _lines(name, file)
    header = _header(name, lines)
    body = _Body(SeriesBuilder())
    error = None
    try:
        _body(name, lines, body)
    except CorruptRecordingError as exc:
        if strict:
            raise
        error = exc
    samples, poses = body.samples.build(header.pose_frame)
    end = None if error is not None else body.end
    return Recording(header, tuple(body.events), end, name, error, samples, poses)
