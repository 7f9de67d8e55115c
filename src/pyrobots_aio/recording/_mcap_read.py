"""Reading an MCAP recording (`McapRecorder`) back into a `Recording`, as `load` does.

The file is read as a stream, record by record, so that a recording cut short
(a crash) is read up to where it stops. The file is untrusted, so the records
are read here rather than by the ``mcap`` package's reader (whose parsers of
single records are used): a record outside a chunk is at most `MAX_RECORD`
bytes, and a chunk is decompressed as a stream, piece by piece, counting the
bytes it actually produces. A chunk may produce no more than the size it
declares, which is at most `CHUNK_LIMIT`, and the chunks of a file together
at most `INFLATION` times the bytes of the file (beyond `SLACK`). A
decompression bomb (kilobytes that declare a hundred bytes and inflate to
gigabytes) is stopped after the bytes declared, and memory and time follow
the size of the file. Errors name the chunk by its byte offset in the file.
"""

from __future__ import annotations

import io
import math
import os
import struct
import zlib
from dataclasses import dataclass, field
from typing import IO, TYPE_CHECKING, Any, NoReturn, cast

from pyrobots_aio import CorruptRecordingError, ExecEvent, RecordingError
from pyrobots_aio.telemetry import EVENT, POSE_IN_FRAME, SAMPLE

from ._mcap import origin_ns
from ._recording import (
    MAX_RECORD,
    MCAP_MAGIC,
    Recording,
    SeriesBuilder,
    brief,
    event_from_json,
    loop_time,
    parse_json,
    read_header,
)

if TYPE_CHECKING:
    from collections.abc import Iterator
    from typing import BinaryIO, Protocol

    from mcap.records import Channel, McapRecord, Message, Metadata

    class _Readable(Protocol):
        def read(self, size: int = -1, /) -> bytes: ...


CHUNK_LIMIT = 256 * 1024 * 1024
"""Largest chunk (uncompressed bytes) read; `McapRecorder` writes chunks of about 1 MiB."""
INFLATION = 50
"""Most bytes the chunks of a file may inflate to, per byte of the file (beyond `SLACK`).

`McapRecorder`'s chunks inflate 7 to 8 times (zstd; 8.3 for a run of identical
no-op actions); a decompression bomb, thousands of times. Skipping a record
costs about 0.35 us, so a crafted file of the smallest records (9 bytes) costs
at most about 2 s per megabyte; reading a real recording, about 0.2 s."""
SLACK = 1024 * 1024
PIECE = 64 * 1024
"""Compressed bytes read at a time, and decompressed bytes skipped at a time."""
_HEAD = struct.Struct("<BQ")
"""A record's opcode and length."""
_CHUNK_FIELDS = struct.Struct("<QQQII")
"""A chunk's start and end times, uncompressed size and CRC, and the length of its compression."""
_LENGTH = struct.Struct("<Q")


class _Bad(Exception):
    """A problem with one message."""


class _BadFile(Exception):
    """A problem with the file's records: the message says which, by byte offset."""


class _FileEnds(EOFError):
    """The file ends inside a record."""


def _exact(file: _Readable, size: int) -> bytes:
    data = file.read(size)
    if len(data) < size:
        raise _FileEnds
    return data


class _Window:
    """The compressed bytes of one chunk, read from the file as the decompressor asks."""

    def __init__(self, file: BinaryIO, size: int) -> None:
        self._file = file
        self._left = size

    def read(self, size: int = -1, /) -> bytes:
        size = self._left if size < 0 else min(size, self._left)
        data = _exact(self._file, size)
        self._left -= size
        return data


class _Inflated:
    """The bytes a chunk inflates to: read exactly, never produced past the size it declares.

    They are produced a piece (`PIECE`) at a time into a buffer, which the
    records are cut from; their CRC is taken as they come.
    """

    def __init__(self, stream: _Readable, declared: int, where: str) -> None:
        self._stream = stream
        self.declared = declared
        self.left = declared
        """Bytes not read yet."""
        self.crc = 0
        self._produced = 0
        self._buffer = b""
        self._at = 0
        self._where = where

    def read(self, size: int) -> bytes:
        """The next ``size`` bytes (``size`` at most `left`)."""
        end = self._at + size
        if end > len(self._buffer):
            self._fill(size)
            end = size
        data = self._buffer[self._at : end]
        self._at = end
        self.left -= size
        return data

    def _fill(self, size: int) -> None:
        """Make the buffer start at the next byte and hold ``size`` bytes or more."""
        parts = [self._buffer[self._at :]]
        have = len(parts[0])
        while have < size:  # size <= left: not past the size declared
            part = self._stream.read(min(max(PIECE, size - have), self.declared - self._produced))
            if not part:
                msg = f"{self._where} inflates to {self._produced} bytes, not the {self.declared}"
                raise _BadFile(msg + " it declares")
            self.crc = zlib.crc32(part, self.crc)
            self._produced += len(part)
            have += len(part)
            parts.append(part)
        self._buffer, self._at = b"".join(parts), 0

    def skip(self, size: int) -> None:
        while size:
            size -= len(self.read(min(size, PIECE)))

    def overrun(self, start: int) -> NoReturn:
        """A record at ``start`` claims more than is left: the chunk is a bomb, or corrupt."""
        self.skip(self.left)
        self.check_end()
        msg = f"{self._where}: the record at byte {start} of its data runs past its end"
        raise _BadFile(msg)

    def check_end(self) -> None:
        """All declared bytes are read: no more may come."""
        if self._stream.read(1):
            msg = (
                f"{self._where} inflates past the {self.declared} bytes it declares "
                "(a decompression bomb?)"
            )
            raise _BadFile(msg)


def _decompressor(compression: str, window: _Window, where: str) -> _Readable:
    """A stream of the bytes ``window`` decompresses to, produced as they are read."""
    source = cast("IO[bytes]", window)
    if compression == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().stream_reader(source, read_size=PIECE)
    if compression == "lz4":
        import lz4.frame

        return cast("_Readable", lz4.frame.LZ4FrameFile(source, mode="rb"))
    if compression == "":
        return window
    raise _BadFile(f"{where} is compressed with {brief(compression)}; known: zstd, lz4, none")


_MESSAGE = struct.Struct("<HIQQ")
"""A message's channel, sequence number, log and publish times; its data follow."""


_MESSAGE_OP, _CHUNK, _FOOTER = 0x05, 0x06, 0x02
_READ = frozenset({0x03, 0x04, _MESSAGE_OP, 0x0C})
"""The records read: Schema, Channel, Message, Metadata (others are skipped)."""


class _Records:
    """The records of an MCAP file, chunks opened, within the bounds of the module notes."""

    def __init__(self, file: BinaryIO) -> None:
        from mcap.records import Channel, Message, Metadata, Schema  # the optional extra

        self._file = file
        self._size = os.fstat(file.fileno()).st_size
        self._inflated = 0
        self._message = Message
        self._others: dict[int, Any] = {0x03: Schema, 0x04: Channel, 0x0C: Metadata}

    def _parse(self, opcode: int, body: bytes) -> McapRecord:
        """The record ``body`` holds; `ValueError` if it is too short for its fields."""
        if opcode == _MESSAGE_OP:  # most records: read here, faster than by mcap's stream
            if len(body) < _MESSAGE.size:
                raise ValueError("a malformed Message record (shorter than its fields)")
            channel, sequence, log_time, publish_time = _MESSAGE.unpack_from(body)
            data = body[_MESSAGE.size :]
            return self._message(
                channel_id=channel,
                log_time=log_time,
                data=data,
                publish_time=publish_time,
                sequence=sequence,
            )
        from mcap.data_stream import ReadDataStream
        from mcap.exceptions import EndOfFile

        kind = self._others[opcode]
        try:
            record: McapRecord = kind.read(ReadDataStream(io.BytesIO(body)))
        except (EndOfFile, struct.error, UnicodeDecodeError) as exc:
            problem = "shorter than its fields" if isinstance(exc, EndOfFile) else exc
            raise ValueError(f"a malformed {kind.__name__} record ({problem})") from None
        return record

    def __iter__(self) -> Iterator[McapRecord]:
        file = self._file
        file.seek(len(MCAP_MAGIC))
        while True:
            offset = file.tell()
            opcode, length = _HEAD.unpack(_exact(file, _HEAD.size))
            if length > self._size - file.tell():
                raise _FileEnds
            if opcode == _FOOTER:
                return
            if opcode == _CHUNK:
                yield from self._chunk(offset, length)
            elif opcode in _READ:
                body = self._body(length, offset)
                try:
                    record = self._parse(opcode, body)
                except ValueError as exc:
                    raise _BadFile(f"the record at byte {offset}: {exc}") from None
                yield record
            else:  # indexes, attachments, ... not needed here
                file.seek(length, os.SEEK_CUR)

    def _body(self, length: int, offset: int) -> bytes:
        if length > MAX_RECORD:
            msg = (
                f"the record at byte {offset} is {length} bytes long (the most read: {MAX_RECORD})"
            )
            raise _BadFile(msg)
        return _exact(self._file, length)

    def _chunk(self, offset: int, length: int) -> Iterator[McapRecord]:
        where = f"the chunk at byte {offset}"
        file, end = self._file, offset + _HEAD.size + length
        _, _, declared, crc, name_length = _CHUNK_FIELDS.unpack(_exact(file, _CHUNK_FIELDS.size))
        if name_length > 16:
            raise _BadFile(f"{where} names a compression of {name_length} bytes (not MCAP?)")
        compression = _exact(file, name_length).decode("utf-8", "replace")
        (size,) = _LENGTH.unpack(_exact(file, _LENGTH.size))
        if size > end - file.tell():
            raise _BadFile(f"{where} holds {size} bytes of data in a record of {length}")
        self._admit(declared, end, where)
        data = _Inflated(_decompressor(compression, _Window(file, size), where), declared, where)
        try:
            yield from self._inner(data, where)
        except (_BadFile, _FileEnds):
            raise
        except Exception as exc:  # the decompressors raise their own kinds on damaged data
            msg = f"{where}: cannot decompress it ({compression}: {type(exc).__name__}: {exc})"
            raise _BadFile(msg) from None
        if crc and data.crc != crc:
            raise _BadFile(f"{where}: its data fail their CRC check (damaged)")
        file.seek(end)

    def _inner(self, data: _Inflated, where: str) -> Iterator[McapRecord]:
        """The records in a chunk's data (Schema, Channel, Message)."""
        while data.left:
            start = data.declared - data.left
            if data.left < _HEAD.size:
                data.overrun(start)
            opcode, length = _HEAD.unpack(data.read(_HEAD.size))
            if length > data.left:
                data.overrun(start)
            if opcode not in _READ:
                data.skip(length)
                continue
            if length > MAX_RECORD:
                problem = f"is {length} bytes long (the most read: {MAX_RECORD})"
                raise _BadFile(f"{where}, record at byte {start} of its data {problem}")
            try:
                record = self._parse(opcode, data.read(length))
            except ValueError as exc:
                raise _BadFile(f"{where}, record at byte {start} of its data: {exc}") from None
            yield record
        data.check_end()

    def _admit(self, declared: int, end: int, where: str) -> None:
        """Refuse a chunk that would inflate beyond `CHUNK_LIMIT` or the file's `INFLATION`."""
        if declared > CHUNK_LIMIT:
            msg = f"{where} declares {declared} bytes (the most read: {CHUNK_LIMIT})"
            raise _BadFile(msg)
        self._inflated += declared
        budget = SLACK + INFLATION * min(end, self._size)
        if self._inflated > budget:
            msg = (
                f"{where} would inflate the file's chunks to {self._inflated} bytes, more than "
                f"{INFLATION} times the {end} bytes of file they come from (a decompression bomb?)"
            )
            raise _BadFile(msg)


def _records(path: str, file: BinaryIO) -> Iterator[McapRecord]:
    try:
        return iter(_Records(file))
    except ImportError as exc:
        msg = (
            f"{path} is an MCAP recording, and reading it needs the 'mcap' package, which is "
            'optional: install it with pip install -e ".[mcap]" from a checkout (or pip '
            "install mcap)"
        )
        raise RecordingError(msg) from exc


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
            self.end = None if end is None else loop_time(end, "end")
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
            time = loop_time(body.get("time"), "time")
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
        raise _Bad(f"{name!r} must be a number, got {brief(value)}")
    return float(value)


def _event_line(body: object) -> dict[str, Any]:
    """An event message as the event line of a JSON Lines recording."""
    if not isinstance(body, dict):
        raise _Bad(f"expected a JSON object, got {type(body).__name__}")
    line = {k: body.get(k) for k in ("kind", "action", "name", "data")}
    line["t"] = body.get("time")
    return line


NO_HEADER = "no pyrobots_aio metadata record: not a pyrobots_aio recording"


def load_mcap(path: str, file: BinaryIO, *, strict: bool = True) -> Recording:
    """Read an MCAP recording from ``file``, open on ``path`` (see `load`)."""
    reading = _Reading(path)
    error = None
    try:
        for record in _records(path, file):
            reading.take(record)
    except RecordingError:  # a bad or newer header: nothing to show
        raise
    except Exception as exc:  # the mcap parsers raise many kinds on a damaged record
        where = reading.messages + 1
        error = CorruptRecordingError(path, where, _problem(exc))
        if strict or reading.header is None:
            raise error from None
    if reading.header is None:
        raise CorruptRecordingError(path, 1, NO_HEADER)
    samples, poses = reading.samples.build(reading.header.pose_frame)
    end = reading.end if reading.closed and error is None else None
    return Recording(reading.header, tuple(reading.events), end, path, error, samples, poses)


def _problem(exc: Exception) -> str:
    if isinstance(exc, _BadFile):
        return str(exc)
    if isinstance(exc, _Bad | ValueError):
        return f"message {exc}"
    if isinstance(exc, EOFError):
        return "the MCAP file ends early (was the recorder closed?)"
    return f"not a readable MCAP file ({type(exc).__name__}: {exc})"
