"""The MCAP recorder (the ``mcap`` extra): a run on Foxglove's channels, in one file.

The channels are those of the live view (``Robot(serve=PORT)``): the
executive's events on ``/pyrobots/actions``, ``/pyrobots/resources`` and
``/pyrobots/monitors`` (JSON schema ``pyrobots_aio.ExecEvent``), each state key
on ``/pyrobots/state/<key>`` (plot ``.value``), the pose on ``/pyrobots/pose``
(``foxglove.PoseInFrame``), ``map`` -> ``base_link`` on ``/tf``
(``foxglove.FrameTransforms``), notable events and the library's log records
on ``/pyrobots/log`` (``foxglove.Log``), and a simulated robot's arena (walls,
obstacles, dock: the header's floor plan) on ``/pyrobots/arena``
(``foxglove.SceneUpdate``, once, at the start), for Foxglove's 3D panel.
Every message is strict JSON.
The header facts (robot, seed, floor plan ...) are the ``pyrobots_aio``
metadata record, each value JSON-encoded; ``pyrobots_aio.end`` is written on
close. `load` reads the file back into the same `Recording` as the JSON Lines
recorder gives.
"""

from __future__ import annotations

import datetime
import logging
import os
from typing import TYPE_CHECKING, Any

from pyrobots_aio import RecordingError
from pyrobots_aio.lowlevel import strict_json
from pyrobots_aio.telemetry import (
    FIXED_CHANNELS,
    SCHEMAS,
    FoxgloveChannels,
    LogForwarder,
    Message,
)

from ._recorder import Recorder, RecordingOptions

if TYPE_CHECKING:
    from collections.abc import Collection, Mapping
    from typing import BinaryIO

    from mcap.writer import Writer

    from pyrobots_aio import ExecEvent
    from pyrobots_aio.poses import Pose2D

    from ._recording import RecordingHeader

LOGGER = "pyrobots_aio"
"""The logger whose records go to ``/pyrobots/log`` with ``logs=True``."""


def _writer_class() -> type[Writer]:
    try:
        from mcap.writer import Writer
    except ImportError as exc:
        msg = (
            "McapRecorder needs the 'mcap' package, which is optional: "
            'install it with pip install -e ".[mcap]" from a checkout (or pip install mcap), '
            "or record with JsonlRecorder"
        )
        raise RecordingError(msg) from exc
    return Writer


def origin_ns(header: Mapping[str, Any]) -> int:
    """The wall-clock start of a run in ns since 1970, from its header's ``created``."""
    created = header.get("created")
    if not isinstance(created, str):
        return 0
    try:
        return round(datetime.datetime.fromisoformat(created).timestamp() * 1e9)
    except ValueError:
        return 0


class McapSink:
    """A `Sink` that writes an MCAP file, which Foxglove opens and `load` reads.

    Needs the ``mcap`` extra; without it, creating one raises `RecordingError`
    naming the extra.

    Args:
        path: The file to write (replaced if it exists).
        logs: Also record the records of the ``pyrobots_aio`` logger (those its
            level lets through) on ``/pyrobots/log``, from open to close.
    """

    def __init__(self, path: str | os.PathLike[str], *, logs: bool = False) -> None:
        self._writer_class = _writer_class()
        self.path = os.fspath(path)
        self.logs = logs
        self._file: BinaryIO | None = None
        self._writer: Writer | None = None
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        self._foxglove = FoxgloveChannels(0, 0.0)
        self._forwarder: LogForwarder | None = None
        self._count = 0  # events and state writes

    def open(self, header: RecordingHeader) -> None:
        """Create the file: the header as metadata, the schemas and the fixed channels."""
        facts = header.to_json()
        self._file = open(self.path, "wb")  # noqa: SIM115 (closed in close)
        writer = self._writer = self._writer_class(self._file)
        writer.start(profile="", library="pyrobots_aio")
        writer.add_metadata("pyrobots_aio", {k: strict_json(v).decode() for k, v in facts.items()})
        self._foxglove = FoxgloveChannels(
            origin_ns(facts),
            float("nan") if header.t0 is None else float(header.t0),
            header.pose_frame or "base_link",
        )
        self._schemas = {
            name: writer.register_schema(name, "jsonschema", strict_json(schema))
            for name, schema in SCHEMAS.items()
        }
        for topic, schema in FIXED_CHANNELS.items():
            self._channel(topic, schema)
        if header.floor_plan:
            self._write(self._foxglove.arena(header.floor_plan))
        if self.logs:
            self._forwarder = LogForwarder(self._foxglove, self._write)
            logging.getLogger(LOGGER).addHandler(self._forwarder)

    def _channel(self, topic: str, schema: str) -> int:
        channel = self._channels.get(topic)
        if channel is None and self._writer is not None:
            channel = self._writer.register_channel(topic, "json", self._schemas[schema])
            self._channels[topic] = channel
        return channel if channel is not None else 0

    def _write(self, message: Message) -> None:
        writer = self._writer
        if writer is None:
            return
        channel = self._channel(message.topic, message.schema)
        stamp = message.log_time
        writer.add_message(channel, stamp, message.data, stamp)

    def write_event(self, event: ExecEvent) -> None:
        """Write the event on its channel (and a log line if it is a notable one)."""
        self._count += 1
        foxglove = self._foxglove
        if foxglove.t0 != foxglove.t0:  # NaN: no loop at open; the first event is the origin
            foxglove.t0 = event.time
        for message in foxglove.event(event):
            self._write(message)

    def write_samples(self, time: float, values: Mapping[str, object], pose: Pose2D | None) -> None:
        """Write each state value on its key's channel, and the pose and transform."""
        self._count += 1
        foxglove = self._foxglove
        if foxglove.t0 != foxglove.t0:
            foxglove.t0 = time
        for message in foxglove.samples(time, values, pose):
            self._write(message)

    def flush(self) -> None:
        """Nothing to do: the MCAP writer writes its chunks as they fill."""

    def close(self, end: float | None) -> None:
        """Write the end metadata and the MCAP summary; close the file."""
        if self._forwarder is not None:
            logging.getLogger(LOGGER).removeHandler(self._forwarder)
            self._forwarder = None
        writer, file = self._writer, self._file
        self._writer = self._file = None
        if writer is not None:
            writer.add_metadata(
                "pyrobots_aio.end", {"end": strict_json(end).decode(), "events": str(self._count)}
            )
            writer.finish()  # type: ignore[no-untyped-call]
        if file is not None:
            file.close()

    def __repr__(self) -> str:
        state = "closed" if self._writer is None else "open"
        return f"<McapSink {self.path!r} {state}>"


class McapRecorder(Recorder[McapSink]):
    """Records a robot's run to an MCAP file (a `McapSink`) that Foxglove opens and `load` reads.

    Needs the ``mcap`` extra; without it, creating one raises `RecordingError`
    naming the extra.

    Args:
        path: The file to write (replaced if it exists).
        state_keys: State keys to sample (None: every key; see `RecordingOptions`).
        sample_rate: None (default): every change; a number downsamples numbers
            and the pose to at most that many samples per second.
        pose_frame: The frame whose pose in ``map`` is recorded (None: none).
        metadata: Free facts for the file's ``pyrobots_aio`` metadata record.
        logs: Also record the records of the ``pyrobots_aio`` logger (those its
            level lets through) on ``/pyrobots/log`` while attached.

    Examples:
        >>> from pyrobots_aio.sim import SimRobot
        >>> from pyrobots_aio.recording import McapRecorder
        >>> robot = SimRobot()  # doctest: +SKIP
        >>> with McapRecorder("run.mcap").attach(robot):  # doctest: +SKIP
        ...     ...  # async with robot: ...
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        state_keys: Collection[str] | None = None,
        sample_rate: float | None = None,
        pose_frame: str | None = "base_link",
        metadata: Mapping[str, object] | None = None,
        logs: bool = False,
    ) -> None:
        options = RecordingOptions(state_keys, sample_rate, pose_frame, metadata or {})
        super().__init__(McapSink(path, logs=logs), options)

    @property
    def path(self) -> str:
        """The file written."""
        return self.sink.path

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<McapRecorder {self.path!r} {state}, {self._count} events>"
