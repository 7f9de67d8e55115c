"""The JSON Lines recorder: one JSON object per line, written in bulk.

``on_event`` runs inside the executive, once per event, so it does as little
as it can. Action events (spawned, started, finished: the bulk of a run) are
gathered in a small batch and encoded together, each with the cached end of
its line (kind, name, data: the same from one action to the next of a name);
other events are encoded at once, so that a state sample keeps the value it
had. Lines are written when ``buffer_size`` of them are waiting,
``flush_interval`` seconds (loop time) after the first, and on close: a write
costs a fraction of a millisecond, and a crash loses at most that much.
Measured on the action benchmark (tests/bench/bench_recording.py), recording
costs the executive about 1.8x, of which about 1.45x is the instrumentation
hook itself (a no-op instrument) and most of the rest turning loop times
into text (``repr`` of a float). On the lockstep random walk, recording every
sensor key and the pose at 50 Hz costs about 1.4x: a sample line is built by
hand from its finite floats and booleans (their ``repr``), other values go
through the JSON encoder.

The lines are strict JSON: a non-finite float (NaN, Infinity), which JSON
cannot write, is recorded as null.

A write that fails (a full disk, a file-size limit) stops the recording, not
the robot: one warning says so, the file is cut back to its last whole line
(a failed write can leave half a line behind), what comes after is dropped,
and closing (`Recorder.close`) raises `RecordingError`. The file then reads as a
recording without its end record (``Recording.complete`` is False).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
from typing import IO, TYPE_CHECKING, Any

from pyrobots_aio import EventKind, RecordingError
from pyrobots_aio.lowlevel import jsonable as _jsonable
from pyrobots_aio.lowlevel import null_nonfinite as _null_nonfinite

from ._recorder import Recorder, RecordingOptions

if TYPE_CHECKING:
    from collections.abc import Callable, Collection, Mapping

    from pyrobots_aio import ExecEvent
    from pyrobots_aio.poses import Pose2D

    from ._recording import RecordingHeader

_log = logging.getLogger("pyrobots_aio.recording")


def _strict(encode: Callable[[Any], str]) -> Callable[[Any], str]:
    """``encode`` (which refuses NaN and Infinity), retried with those as null."""

    def strict(value: Any) -> str:
        try:
            return encode(value)
        except ValueError:  # "Out of range float values are not JSON compliant"
            return encode(_null_nonfinite(value))

    return strict


_encode = _strict(
    json.JSONEncoder(
        separators=(",", ":"),
        ensure_ascii=False,
        check_circular=False,
        allow_nan=False,
        default=_jsonable,
    ).encode
)
"""Compact strict JSON; what ``json`` cannot encode goes through `_jsonable`."""


def _data_encoder() -> Callable[[Mapping[str, object]], str]:
    """An encoder like `_encode` for the event path, built once.

    ``JSONEncoder.encode`` builds a C encoder on every call; building it once
    halves the cost of a line.
    """
    make = getattr(json.encoder, "c_make_encoder", None)
    if make is None:  # Pythons without the C accelerator
        return _encode
    # markers, default, encoder, indent, key and item separators, sort_keys, skipkeys, allow_nan
    encoder = make(
        None, _jsonable, json.encoder.encode_basestring, None, ":", ",", False, False, False
    )
    return _strict(lambda data: "".join(encoder(data, 0)))


_encode_data = _data_encoder()
_BATCHED = frozenset(
    {EventKind.ACTION_SPAWNED, EventKind.ACTION_STARTED, EventKind.ACTION_FINISHED}
)
"""Kinds encoded in batches, with cached line ends: their data are the executive's own
ints, strings and None, which do not change once emitted."""
BATCH = 64
"""Most action events kept before they are encoded: few enough that they die young
(events kept longer would outlive garbage-collector generations and slow every collection)."""


class JsonlSink:
    """A `Sink` that writes a JSON Lines file, which `load` reads back.

    Args:
        path: The file to write (replaced if it exists).
        buffer_size: Lines buffered before a write.
        flush_interval: Loop seconds after which buffered lines are written anyway.
    """

    def __init__(
        self, path: str | os.PathLike[str], *, buffer_size: int = 1000, flush_interval: float = 1.0
    ) -> None:
        if isinstance(buffer_size, bool) or not isinstance(buffer_size, int) or buffer_size < 1:
            msg = f"buffer_size must be a positive number of events, got {buffer_size!r}"
            raise ValueError(msg)
        if not flush_interval > 0:
            msg = f"flush_interval must be a positive number of seconds, got {flush_interval!r}"
            raise ValueError(msg)
        self.path = os.fspath(path)
        self.buffer_size = buffer_size
        self.flush_interval = float(flush_interval)
        self._file: IO[str] | None = None
        self._count = 0  # lines written after the header
        self._batch: list[ExecEvent] = []  # action events not yet encoded
        self._batch_size = min(BATCH, buffer_size)
        self._lines: list[str] = []  # encoded, not yet written
        self._keys: dict[str, str] = {}  # each state key's JSON, with its colon
        self._timer: asyncio.TimerHandle | None = None
        self._error: OSError | None = None
        # For each batched kind and action name: the data of its last event and its line end.
        self._ends: dict[EventKind, dict[str | None, tuple[Mapping[str, object], str]]] = {
            kind: {} for kind in _BATCHED
        }

    def open(self, header: RecordingHeader) -> None:
        """Create the file and write the header line."""
        file = open(self.path, "w", encoding="utf-8")  # noqa: SIM115 (closed in close)
        try:
            file.write(_encode(header.to_json()) + "\n")
            file.flush()
        except BaseException:
            with contextlib.suppress(OSError):
                file.close()
            raise
        self._file = file

    def write_event(self, event: ExecEvent) -> None:
        """Take one event: batch it (action events) or encode it now; write when enough wait."""
        if event.kind in _BATCHED:
            batch = self._batch
            batch.append(event)
            if (n := len(batch)) == 1 or n >= self._batch_size:
                self._batched(event.time)
            return
        if self._batch:  # keep the order of events
            self._encode_batch()
        lines = self._lines
        lines.append(self._line(event))
        if len(lines) == 1:
            self._first_pending()
        if len(lines) >= self.buffer_size:
            self._write()

    def write_samples(self, time: float, values: Mapping[str, object], pose: Pose2D | None) -> None:
        """One sample line: the state values written at ``time`` and the pose."""
        if self._batch:  # keep the order of events
            self._encode_batch()
        state = self._state(values) if values else "{}"
        tail = "}\n" if pose is None else f',"pose":[{pose[0]!r},{pose[1]!r},{pose[2]!r}]}}\n'
        lines = self._lines
        lines.append(f'{{"t":{time!r},"state":{state}{tail}')
        if len(lines) == 1:
            self._first_pending()
        if len(lines) >= self.buffer_size:
            self._write()

    def _state(self, values: Mapping[str, object]) -> str:
        """``values`` as a JSON object: finite floats and booleans directly (most sensors)."""
        keys, parts = self._keys, []
        for key, value in values.items():
            name = keys.get(key)
            if name is None:
                name = keys[key] = _encode(key) + ":"
            if type(value) is float and value - value == 0.0:  # a finite float
                parts.append(f"{name}{value!r}")
            elif type(value) is bool:
                parts.append(name + ("true" if value else "false"))
            else:
                parts.append(name + _encode_data({"": value})[4:-1])
        return "{" + ",".join(parts) + "}"

    def _batched(self, time: float) -> None:
        """The batch just got its first event, or is full."""
        if len(self._batch) == 1:
            self._first_pending()
        if len(self._batch) >= self._batch_size:
            self._encode_batch()

    def _first_pending(self) -> None:
        """Something waits to be written: drop it if the file failed, else plan a timed flush."""
        if self._error is not None:
            self._batch.clear()
            self._lines.clear()
            return
        if self._timer is None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                return  # no loop: written when the buffer fills, and on close
            self._timer = loop.call_later(self.flush_interval, self._timed_flush)

    def _timed_flush(self) -> None:
        self._timer = None
        self.flush()

    def flush(self) -> None:
        """Write the buffered lines now."""
        if self._batch:
            self._encode_batch()
        self._write()

    @property
    def error(self) -> OSError | None:
        """The error that stopped the recording (a full disk), or None."""
        return self._error

    def _write(self) -> None:
        lines, file = self._lines, self._file
        if not lines or file is None:
            return
        self._lines = []
        try:
            file.write("".join(lines))
            file.flush()
        except OSError as exc:
            self._fail(exc)
            return
        self._count += len(lines)

    def _fail(self, error: OSError) -> None:
        """Stop recording after a failed write; cut the file back to its last whole line."""
        self._error = error
        file, self._file = self._file, None
        self._batch.clear()
        self._lines.clear()
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if file is not None:
            with contextlib.suppress(OSError):  # its buffer cannot be written either
                file.close()
        try:
            _cut_to_last_line(self.path)
        except OSError as exc:
            _log.debug("cannot cut %s back to its last whole line: %s", self.path, exc)
        _log.warning(
            "recording to %s stopped: %s; the file keeps what was written before, up to "
            "its last whole line, and the robot runs on unrecorded",
            self.path,
            error,
        )

    def _encode_batch(self) -> None:
        batch, self._batch = self._batch, []
        lines, ends = self._lines, self._ends
        for event in batch:
            known = ends[event.kind]
            end = known.get(event.name)
            data = event.data
            # Equal data give the same JSON here: the executive's values are ints, strings, None.
            if end is None or end[0] != data:
                end = known[event.name] = (data, _tail(event, data))
            action = "null" if event.action is None else event.action
            lines.append(f'{{"t":{event.time!r},"action":{action}{end[1]}')
        if len(lines) >= self.buffer_size:
            self._write()

    @staticmethod
    def _line(event: ExecEvent) -> str:
        action = "null" if event.action is None else event.action
        return f'{{"t":{event.time!r},"action":{action}{_tail(event, event.data)}'

    def close(self, end: float | None) -> None:
        """Write what is buffered and the end record; close the file.

        Raises:
            RecordingError: A write failed (a full disk): the file keeps the
                lines written before, up to its last whole line, without an end record.
        """
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        try:
            self.flush()
        finally:  # even if interrupted: the end record, and the file closed
            self._write_end(end)
        if self._error is not None:
            msg = (
                f"recording to {self.path} failed: {self._error}; the file keeps the events "
                "written before, up to its last whole line, without an end record"
            )
            raise RecordingError(msg)
        _log.debug("recorded %d events to %s", self._count, self.path)

    def _write_end(self, end: float | None) -> None:
        file, self._file = self._file, None
        if file is None:
            return
        try:
            file.write(_encode({"end": end, "events": self._count}) + "\n")
            file.close()
        except OSError as exc:
            self._file = file
            self._fail(exc)

    def __repr__(self) -> str:
        state = "failed" if self._error else "closed" if self._file is None else "open"
        return f"<JsonlSink {self.path!r} {state}>"


def _tail(event: ExecEvent, data: Mapping[str, object]) -> str:
    """The end of an event's line: its kind, name and data."""
    name = _encode(event.name)
    encoded = _encode_data(data) if data else "{}"
    return f',"kind":"{event.kind}","name":{name},"data":{encoded}}}\n'


class JsonlRecorder(Recorder[JsonlSink]):
    """Records a robot's run to a JSON Lines file (a `JsonlSink`) that `load` reads back.

    Args:
        path: The file to write (replaced if it exists).
        state_keys: State keys to sample (None: every key; see `RecordingOptions`).
        sample_rate: None (default): every change; a number downsamples numbers
            and the pose to at most that many samples per second.
        pose_frame: The frame whose pose in ``map`` is recorded (None: none).
        metadata: Free JSON-friendly facts for the header.
        buffer_size: Lines buffered before a write.
        flush_interval: Loop seconds after which buffered lines are written anyway.

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot, action
        >>> from pyrobots_aio.recording import JsonlRecorder, load
        >>> @action
        ... async def hello(robot: Robot) -> None:
        ...     await robot.sleep(0.01)
        >>> async def main(path: str) -> None:
        ...     robot = Robot()
        ...     with JsonlRecorder(path).attach(robot):
        ...         async with robot:
        ...             await hello(robot)
        >>> asyncio.run(main("hello.jsonl"))  # doctest: +SKIP
        >>> [e.kind.value for e in load("hello.jsonl").events]  # doctest: +SKIP
        ['action.spawned', 'action.started', 'action.finished']
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        state_keys: Collection[str] | None = None,
        sample_rate: float | None = None,
        pose_frame: str | None = "base_link",
        metadata: Mapping[str, object] | None = None,
        buffer_size: int = 1000,
        flush_interval: float = 1.0,
    ) -> None:
        sink = JsonlSink(path, buffer_size=buffer_size, flush_interval=flush_interval)
        options = RecordingOptions(state_keys, sample_rate, pose_frame, metadata or {})
        super().__init__(sink, options)

    @property
    def path(self) -> str:
        """The file written."""
        return self.sink.path

    @property
    def error(self) -> OSError | None:
        """The error that stopped the recording (a full disk), or None."""
        return self.sink.error

    def __repr__(self) -> str:
        state = "failed" if self.error else "closed" if self.closed else "open"
        return f"<JsonlRecorder {self.path!r} {state}, {self._count} events>"


def _cut_to_last_line(path: str) -> None:
    """Truncate the file at ``path`` just after its last newline (a failed write's half line)."""
    with open(path, "rb+") as file:
        size = file.seek(0, os.SEEK_END)
        end = size
        while end > 0:
            start = max(0, end - 4096)
            file.seek(start)
            newline = file.read(end - start).rfind(b"\n")
            if newline >= 0:
                end = start + newline + 1
                break
            end = start
        if end < size:
            file.truncate(end)
