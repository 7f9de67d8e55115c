"""Reading an MCAP recording (`McapRecorder`) back into a `Recording`, as `load` does.

The file is read as a stream, record by record, so that a recording cut short
(a crash) is read up to where it stops, and memory follows the number of
records: a chunk that claims to be larger than `CHUNK_LIMIT` is refused before
it is decompressed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from pyrobots_aio import CorruptRecordingError, ExecEvent, RecordingError
from pyrobots_aio.telemetry import EVENT, POSE_IN_FRAME, SAMPLE

from ._mcap import origin_ns
from ._recording import (
    Recording,
    SeriesBuilder,
    event_from_json,
    parse_json,
    read_header,
)

if TYPE_CHECKING:
    from collections.abc import Iterator

    from mcap.records import Channel, McapRecord, Message, Metadata

CHUNK_LIMIT = 256 * 1024 * 1024
"""Largest chunk (uncompressed bytes) read; `McapRecorder` writes chunks of about 1 MiB."""


class _Bad(Exception):
    """A problem with one message."""


def _records(path: str, file: Any) -> Iterator[McapRecord]:
    try:
        from mcap.records import Chunk
        from mcap.stream_reader import StreamReader, breakup_chunk
    except ImportError as exc:
        msg = (
            f"{path} is an MCAP recording, and reading it needs the 'mcap' package, which is "
            'optional: install it with pip install -e ".[mcap]" from a checkout (or pip '
            "install mcap)"
        )
        raise RecordingError(msg) from exc
    for record in StreamReader(file, emit_chunks=True, record_size_limit=CHUNK_LIMIT).records:
        if isinstance(record, Chunk):
            if record.uncompressed_size > CHUNK_LIMIT:
                msg = f"a chunk of {record.uncompressed_size} bytes (the most read: {CHUNK_LIMIT})"
                raise _Bad(msg)
            yield from breakup_chunk(record, validate_crc=True)
        else:
            yield record


@dataclass
class _Reading:
    """What the records of the file hold, as they are read."""

    path: str
    header: Any = None
    origin: int = 0
    schemas: dict[int, str] = field(default_factory=dict)
    channels: dict[int, tuple[str, str]] = field(default_factory=dict)
    events: list[ExecEvent] = field(default_factory=list)
    samples: SeriesBuilder = field(default_factory=SeriesBuilder)
    times: dict[int, float] = field(default_factory=dict)
    """The loop time of the latest state message at each message time (for poses)."""
    end: float | None = None
    closed: bool = False
    messages: int = 0

    def take(self, record: McapRecord) -> None:
        from mcap.records import Channel, Message, Metadata, Schema

        if isinstance(record, Schema):
            self.schemas[record.id] = record.name
        elif isinstance(record, Channel):
            self._channel(record)
        elif isinstance(record, Metadata):
            self._metadata(record)
        elif isinstance(record, Message):
            self.messages += 1
            self._message(record)

    def _channel(self, channel: Channel) -> None:
        self.channels[channel.id] = (channel.topic, self.schemas.get(channel.schema_id, ""))

    def _metadata(self, metadata: Metadata) -> None:
        values = {}
        for key, text in metadata.metadata.items():
            try:
                values[key] = parse_json(text)
            except ValueError as exc:
                raise _Bad(f"metadata {metadata.name!r}, {key!r}: {exc}") from None
        if metadata.name == "pyrobots_aio":
            self.header = read_header(self.path, values, line=0)
            self.origin = origin_ns(values)
        elif metadata.name == "pyrobots_aio.end":
            end = values.get("end")
            self.end = float(end) if isinstance(end, int | float) else None
            self.closed = True

    def _message(self, message: Message) -> None:
        if self.header is None:
            raise _Bad("a message before the pyrobots_aio metadata record (not a recording?)")
        topic, schema = self.channels.get(message.channel_id, ("", ""))
        if schema == EVENT:
            self.events.append(event_from_json(_event_line(parse_json(message.data))))
        elif schema == SAMPLE:
            body = parse_json(message.data)
            if not isinstance(body, dict) or not isinstance(body.get("key"), str):
                raise _Bad(f"a state sample without a key on {topic}")
            time = _number(body.get("time"), "time")
            self.samples.add(time, body["key"], body.get("value"))
            self.times[message.log_time] = time
        elif schema == POSE_IN_FRAME:
            self._pose(message)

    def _pose(self, message: Message) -> None:
        body = parse_json(message.data)
        try:
            pose = body["pose"]
            x = _number(pose["position"]["x"], "x")
            y = _number(pose["position"]["y"], "y")
            qz = _number(pose["orientation"]["z"], "z")
            qw = _number(pose["orientation"]["w"], "w")
        except (KeyError, TypeError):
            raise _Bad("a foxglove.PoseInFrame without a position and orientation") from None
        time = self.times.get(message.log_time)
        if time is None:  # no state written with it: from the message time
            t0 = self.header.t0 or 0.0
            time = t0 + (message.log_time - self.origin) / 1e9
        self.samples.add_pose(time, x, y, 2 * math.atan2(qz, qw))


def _number(value: object, name: str) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise _Bad(f"{name!r} must be a number, got {value!r}")
    return float(value)


def _event_line(body: object) -> dict[str, Any]:
    """An event message as the event line of a JSON Lines recording."""
    if not isinstance(body, dict):
        raise _Bad(f"expected a JSON object, got {type(body).__name__}")
    line = {k: body.get(k) for k in ("kind", "action", "name", "data")}
    line["t"] = body.get("time")
    return line


def load_mcap(path: str, *, strict: bool = True) -> Recording:
    """Read an MCAP recording (see `load`)."""
    reading = _Reading(path)
    error = None
    with open(path, "rb") as file:
        try:
            for record in _records(path, file):
                reading.take(record)
        except RecordingError:  # a bad or newer header: nothing to show
            raise
        except Exception as exc:  # the mcap reader raises many kinds on a damaged file
            where = reading.messages + 1
            problem = _problem(exc)
            error = CorruptRecordingError(path, where, problem)
            if strict or reading.header is None:
                raise error from None
    samples, poses = reading.samples.build(reading.header.pose_frame)
    end = reading.end if reading.closed and error is None else None
    return Recording(reading.header, tuple(reading.events), end, path, error, samples, poses)


def _problem(exc: Exception) -> str:
    if isinstance(exc, _Bad | ValueError):
        return f"message {exc}"
    name = type(exc).__name__
    if name == "EndOfFile" or isinstance(exc, EOFError):
        return "the MCAP file ends early (was the recorder closed?)"
    return f"not a readable MCAP file ({name}: {exc})"
