"""The MCAP recorder (the ``mcap`` extra): JSON messages on JSON-schema channels.

Foxglove opens the file as it is: the executive events go to
``/pyrobots/actions``, ``/pyrobots/resources`` and ``/pyrobots/monitors``, each
sampled state key to ``/pyrobots/state/<key>`` (plot ``.value``). Message
times are the run's wall-clock start plus the loop time elapsed since, so
Foxglove shows the date of the run; each message also carries the loop time.
Messages are strict JSON, which Foxglove requires: a non-finite float (NaN,
Infinity) is written as null.
"""

from __future__ import annotations

import datetime
import os
from typing import TYPE_CHECKING, Any

from pyrobots_aio import RecordingError

from ._jsonl import _encode
from ._recorder import Recorder

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping
    from typing import BinaryIO

    from mcap.writer import Writer

    from pyrobots_aio import ExecEvent

EVENT_SCHEMA: dict[str, Any] = {
    "title": "pyrobots_aio.ExecEvent",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "loop time (robot.time()), seconds"},
        "kind": {"type": "string", "description": "what happened, e.g. action.finished"},
        "action": {"type": ["integer", "null"], "description": "the action's id"},
        "name": {"type": ["string", "null"], "description": "the action's or monitor's name"},
        "data": {"type": "object", "description": "kind-specific details"},
    },
    "required": ["time", "kind"],
}
"""The JSON schema of executive event messages."""

STATE_SCHEMA: dict[str, Any] = {
    "title": "pyrobots_aio.StateSample",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "loop time of the write, seconds"},
        "key": {"type": "string"},
        "value": {"description": "the value written"},
    },
    "required": ["time", "key", "value"],
}
"""The JSON schema of state sample messages."""

_TOPICS = {"action": "/pyrobots/actions", "resource": "/pyrobots/resources"}


def _writer_class() -> type[Writer]:
    try:
        from mcap.writer import Writer
    except ImportError as exc:
        msg = (
            "McapRecorder needs the 'mcap' package, which is optional: "
            'install it with pip install mcap (or pip install -e ".[mcap]" in a checkout), '
            "or record with JsonlRecorder"
        )
        raise RecordingError(msg) from exc
    return Writer


class McapRecorder(Recorder):
    """Records a robot's events to an MCAP file that Foxglove opens.

    Needs the ``mcap`` extra (``pip install -e ".[mcap]"`` in a checkout); without it,
    creating one raises `RecordingError` naming the extra.

    Args:
        path: The file to write (replaced if it exists).
        state_keys: State keys to sample (see `Recorder`).
        sample_rate: Most samples per second and numeric key (None: every change).
        metadata: Free facts for the file's ``pyrobots_aio`` metadata record.

    Example:
        >>> from pyrobots_aio.sim import SimRobot
        >>> from pyrobots_aio.recording import McapRecorder
        >>> robot = SimRobot()  # doctest: +SKIP
        >>> recorder = McapRecorder("run.mcap", state_keys=["v", "bumper"])  # doctest: +SKIP
        >>> with recorder.attach(robot):  # doctest: +SKIP
        ...     ...  # async with robot: ...
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        state_keys: Iterable[str] = (),
        sample_rate: float | None = 10.0,
        metadata: Mapping[str, object] | None = None,
    ) -> None:
        self._writer_class = _writer_class()
        super().__init__(state_keys=state_keys, sample_rate=sample_rate, metadata=metadata)
        self.path = os.fspath(path)
        self._file: BinaryIO | None = None
        self._writer: Writer | None = None
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        self._origin_ns = 0
        self._t0 = 0.0

    def _open(self, header: Mapping[str, Any]) -> None:
        self._file = open(self.path, "wb")  # noqa: SIM115 (closed in _finish)
        writer = self._writer = self._writer_class(self._file)
        writer.start(profile="", library="pyrobots_aio")
        writer.add_metadata("pyrobots_aio", {k: _encode(v) for k, v in header.items()})
        created = datetime.datetime.fromisoformat(str(header["created"]))
        self._origin_ns = round(created.timestamp() * 1e9)
        t0 = header.get("t0")
        self._t0 = float(t0) if isinstance(t0, int | float) else float("nan")
        self._schemas = {
            "event": writer.register_schema(
                "pyrobots_aio.ExecEvent", "jsonschema", _encode(EVENT_SCHEMA).encode()
            ),
            "state": writer.register_schema(
                "pyrobots_aio.StateSample", "jsonschema", _encode(STATE_SCHEMA).encode()
            ),
        }

    def _channel(self, topic: str, schema: str) -> int:
        channel = self._channels.get(topic)
        if channel is None and self._writer is not None:
            channel = self._writer.register_channel(topic, "json", self._schemas[schema])
            self._channels[topic] = channel
        return channel if channel is not None else 0

    def _record(self, event: ExecEvent) -> None:
        if self._writer is None:
            return
        if self._t0 != self._t0:  # NaN: no loop at open; the first event is the origin
            self._t0 = event.time
        kind = event.kind.value
        if kind == "state.sample":
            topic, schema = f"/pyrobots/state/{event.name}", "state"
            message: dict[str, Any] = {"time": event.time, "key": event.name}
            message["value"] = event.data.get("value")
        else:
            group = kind.partition(".")[0]
            topic, schema = _TOPICS.get(group, "/pyrobots/monitors"), "event"
            message = {"time": event.time, "kind": kind, "action": event.action}
            message.update(name=event.name, data=dict(event.data))
        stamp = self._origin_ns + max(0, round((event.time - self._t0) * 1e9))
        channel = self._channel(topic, schema)
        self._writer.add_message(channel, stamp, _encode(message).encode(), stamp, self._count)

    def _finish(self, end: float | None, count: int) -> None:
        writer, file = self._writer, self._file
        self._writer = self._file = None
        if writer is not None:
            writer.add_metadata("pyrobots_aio.end", {"end": _encode(end), "events": str(count)})
            writer.finish()  # type: ignore[no-untyped-call]
        if file is not None:
            file.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"<McapRecorder {self.path!r} {state}, {self._count} events>"
