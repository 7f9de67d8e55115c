"""The channels a run is shown on in Foxglove: topics, schemas, and JSON messages.

The MCAP recorder (`pyrobots_aio.recording.McapRecorder`) and the live view
(``Robot(serve=PORT)``) publish the same channels, built here:

=========================== ============================ =====================================
topic                       schema                       what
=========================== ============================ =====================================
``/pyrobots/actions``       ``pyrobots_aio.ExecEvent``   action spawned/started/finished/cancel
``/pyrobots/resources``     ``pyrobots_aio.ExecEvent``   resource waits, holds, preemptions
``/pyrobots/monitors``      ``pyrobots_aio.ExecEvent``   monitor firings
``/pyrobots/state/<key>``   ``pyrobots_aio.StateSample`` one state key (plot ``.value``)
``/pyrobots/pose``          ``foxglove.PoseInFrame``     the robot's pose in ``map``
``/tf``                     ``foxglove.FrameTransforms`` ``map`` -> the robot's frame
``/pyrobots/log``           ``foxglove.Log``             notable events and log records
=========================== ============================ =====================================

Every message is JSON (``json`` encoding, ``jsonschema`` schemas), strict: a
non-finite float is written as null. Foxglove recognises its well-known
schemas by name, whatever the encoding. Message times are the run's wall-clock
start plus the loop time elapsed since (so Foxglove shows the date of the
run); the executive's messages also carry the loop time itself.
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
from typing import TYPE_CHECKING, Any, NamedTuple

from .._core._events import (
    ActionAbandonment,
    ActionFinished,
    ActionSpawned,
    CancelEscalated,
    CancelRequested,
    MonitorFired,
    ResourcePreempted,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from .._core._events import ExecEvent
    from ._sampling import Pose2D

__all__ = [
    "ACTIONS",
    "EVENT",
    "FIXED_CHANNELS",
    "FOXGLOVE_LOG",
    "FRAME_TRANSFORMS",
    "LOG",
    "MONITORS",
    "POSE",
    "POSE_IN_FRAME",
    "RESOURCES",
    "SAMPLE",
    "SCHEMAS",
    "STATE_PREFIX",
    "TF",
    "FoxgloveChannels",
    "LogForwarder",
    "Message",
    "finite",
    "jsonable",
    "log_level",
    "strict_json",
]

ACTIONS, RESOURCES, MONITORS = "/pyrobots/actions", "/pyrobots/resources", "/pyrobots/monitors"
STATE_PREFIX = "/pyrobots/state/"
POSE, TF, LOG = "/pyrobots/pose", "/tf", "/pyrobots/log"
MAP = "map"
EVENT, SAMPLE = "pyrobots_aio.ExecEvent", "pyrobots_aio.StateSample"
"""The schema names of the executive's own JSON channels: its events, and state samples."""
POSE_IN_FRAME, FRAME_TRANSFORMS, FOXGLOVE_LOG = (
    "foxglove.PoseInFrame",
    "foxglove.FrameTransforms",
    "foxglove.Log",
)
"""The Foxglove well-known schemas the pose, ``/tf`` and log channels use."""

_TIME = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
    },
}


def _numbers(title: str, names: str) -> dict[str, Any]:
    return {
        "title": title,
        "type": "object",
        "properties": {name: {"type": "number"} for name in names},
        "required": list(names),
    }


_VECTOR3, _QUATERNION = _numbers("foxglove.Vector3", "xyz"), _numbers("foxglove.Quaternion", "xyzw")
_TRANSFORM = {
    "title": "foxglove.FrameTransform",
    "type": "object",
    "properties": {
        "timestamp": _TIME,
        "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"},
        "translation": _VECTOR3,
        "rotation": _QUATERNION,
    },
    "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"],
}
_LEVELS = ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL")

SCHEMAS: dict[str, dict[str, Any]] = {
    EVENT: {
        "title": EVENT,
        "type": "object",
        "properties": {
            "time": {"type": "number", "description": "loop time (robot.time()), seconds"},
            "kind": {"type": "string", "description": "what happened, e.g. action.finished"},
            "action": {"type": ["integer", "null"], "description": "the action's id"},
            "name": {"type": ["string", "null"], "description": "the action's or monitor's name"},
            "data": {"type": "object", "description": "kind-specific details"},
        },
        "required": ["time", "kind"],
    },
    SAMPLE: {
        "title": SAMPLE,
        "type": "object",
        "properties": {
            "time": {"type": "number", "description": "loop time of the write, seconds"},
            "key": {"type": "string"},
            "value": {"description": "the value written"},
        },
        "required": ["time", "key", "value"],
    },
    POSE_IN_FRAME: {
        "title": POSE_IN_FRAME,
        "type": "object",
        "properties": {
            "timestamp": _TIME,
            "frame_id": {"type": "string"},
            "pose": {
                "title": "foxglove.Pose",
                "type": "object",
                "properties": {"position": _VECTOR3, "orientation": _QUATERNION},
                "required": ["position", "orientation"],
            },
        },
        "required": ["timestamp", "frame_id", "pose"],
    },
    FRAME_TRANSFORMS: {
        "title": FRAME_TRANSFORMS,
        "type": "object",
        "properties": {"transforms": {"type": "array", "items": _TRANSFORM}},
        "required": ["transforms"],
    },
    FOXGLOVE_LOG: {
        "title": FOXGLOVE_LOG,
        "type": "object",
        "properties": {
            "timestamp": _TIME,
            "level": {
                "title": "foxglove.LogLevel",
                "oneOf": [{"title": n, "const": i} for i, n in enumerate(_LEVELS)],
            },
            "message": {"type": "string"},
            "name": {"type": "string"},
            "file": {"type": "string"},
            "line": {"type": "integer", "minimum": 0},
        },
        "required": ["timestamp", "level", "message", "name", "file", "line"],
    },
}
"""Each schema's JSON schema, by schema name (Foxglove's own names for its well-known ones)."""

FIXED_CHANNELS = {
    ACTIONS: EVENT,
    RESOURCES: EVENT,
    MONITORS: EVENT,
    POSE: POSE_IN_FRAME,
    TF: FRAME_TRANSFORMS,
    LOG: FOXGLOVE_LOG,
}
"""The channels every run has (state channels come with their keys)."""
_GROUP_TOPICS = {"action": ACTIONS, "resource": RESOURCES}
DEBUG, INFO, WARNING, ERROR, FATAL = 1, 2, 3, 4, 5


class Message(NamedTuple):
    """One message: its topic, its schema's name, its JSON bytes, its time (ns since 1970)."""

    topic: str
    schema: str
    data: bytes
    log_time: int


def jsonable(value: object) -> object:
    """Make what ``json`` cannot encode encodable: numpy values, sets, anything else by repr."""
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist):
        return tolist()
    if isinstance(value, set | frozenset | tuple):
        return list(value)
    return repr(value)


def finite(value: object) -> object:
    """``value`` with each non-finite float (NaN, Infinity) replaced by None, for strict JSON."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, str | int):
        return value
    if isinstance(value, dict):
        return {
            repr(k) if isinstance(k, float) and not math.isfinite(k) else k: finite(v)
            for k, v in value.items()
        }
    if isinstance(value, list | tuple):
        return [finite(v) for v in value]
    return finite(jsonable(value))


def strict_json(value: object) -> bytes:
    """Compact strict JSON, as UTF-8 (NaN and Infinity become null)."""
    try:
        text = json.dumps(value, separators=(",", ":"), allow_nan=False, default=jsonable)
    except ValueError:  # "Out of range float values are not JSON compliant"
        text = json.dumps(finite(value), separators=(",", ":"), default=jsonable)
    return text.encode()


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _quaternion(yaw: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


class FoxgloveChannels:
    """Turns a run's events, samples and log lines into `Message` values.

    Args:
        origin_ns: The wall-clock time of the run's start, in ns since 1970.
        t0: The loop time at that start.
        frame: The robot frame whose pose is published (``base_link``).
    """

    def __init__(self, origin_ns: int, t0: float, frame: str = "base_link") -> None:
        self.origin_ns = origin_ns
        self.t0 = t0
        self.frame = frame
        self._names: dict[int, str] = {}

    def stamp(self, time: float) -> int:
        """The message time of loop time ``time`` (never before the start)."""
        return self.origin_ns + max(0, round((time - self.t0) * 1e9))

    def event(self, event: ExecEvent) -> list[Message]:
        """The executive event on its channel, and a log line if it is a notable one."""
        kind = event.kind.value
        topic = _GROUP_TOPICS.get(kind.partition(".")[0], MONITORS)
        body = {"time": event.time, "kind": kind, "action": event.action, "name": event.name}
        body["data"] = event.data
        stamp = self.stamp(event.time)
        messages = [Message(topic, EVENT, strict_json(body), stamp)]
        line = self._notable(event)
        if line is not None:
            messages.append(self.log(event.time, line[0], "pyrobots_aio.executive", line[1]))
        return messages

    def _label(self, ident: int | None) -> str:
        if ident is None:
            return "outside any action"
        return f"{self._names.get(ident, '?')}#{ident}"

    def _notable(self, event: ExecEvent) -> tuple[int, str] | None:
        ident = event.action
        if isinstance(event, ActionSpawned) and ident is not None:
            self._names[ident] = event.name or "?"
            return None
        who = self._label(ident)
        match event:
            case ActionFinished(outcome=outcome, error=error):
                self._names.pop(ident, None) if ident is not None else None
                if outcome == "failed":
                    return ERROR, f"{who} failed: {error}"
            case CancelRequested(reason=reason, by=by):
                return INFO, f"{who} cancelled by {self._label(by)}: {reason}"
            case ResourcePreempted(resource=resource):
                return WARNING, f"{who} preempted for {resource!r}"
            case CancelEscalated():
                return WARNING, f"{who} overran its cancel grace: cancelled again"
            case ActionAbandonment():
                return ERROR, f"{who} ignored cancellation and was abandoned"
            case MonitorFired():
                return INFO, f"monitor {event.name} fired"
        return None

    def samples(
        self, time: float, values: Mapping[str, object], pose: Pose2D | None
    ) -> list[Message]:
        """A state write: one message per key, and the pose and transform."""
        stamp = self.stamp(time)
        messages = [
            Message(
                STATE_PREFIX + key,
                SAMPLE,
                strict_json({"time": time, "key": key, "value": value}),
                stamp,
            )
            for key, value in values.items()
        ]
        if pose is not None:
            x, y, yaw = pose
            position = {"x": x, "y": y, "z": 0.0}
            in_frame = {"timestamp": _stamp(stamp), "frame_id": MAP}
            in_frame["pose"] = {"position": position, "orientation": _quaternion(yaw)}
            transform = {"timestamp": _stamp(stamp), "parent_frame_id": MAP}
            transform.update(child_frame_id=self.frame, translation=position)
            transform["rotation"] = _quaternion(yaw)
            messages.append(Message(POSE, POSE_IN_FRAME, strict_json(in_frame), stamp))
            messages.append(
                Message(TF, FRAME_TRANSFORMS, strict_json({"transforms": [transform]}), stamp)
            )
        return messages

    def log(
        self, time: float, level: int, name: str, text: str, *, file: str = "", line: int = 0
    ) -> Message:
        """A ``foxglove.Log`` line."""
        stamp = self.stamp(time)
        body = {"timestamp": _stamp(stamp), "level": level, "message": text, "name": name}
        body.update(file=file, line=max(0, line))
        return Message(LOG, FOXGLOVE_LOG, strict_json(body), stamp)


def log_level(levelno: int) -> int:
    """The ``foxglove.LogLevel`` of a `logging` level number."""
    for threshold, level in (
        (logging.CRITICAL, FATAL),
        (logging.ERROR, ERROR),
        (logging.WARNING, WARNING),
        (logging.INFO, INFO),
    ):
        if levelno >= threshold:
            return level
    return DEBUG


class LogForwarder(logging.Handler):
    """While attached to a logger, turns its records into ``foxglove.Log`` messages.

    Only records emitted on the thread of the running event loop are taken
    (they are stamped with the loop's clock); ``send`` receives each message.
    """

    def __init__(self, channels: FoxgloveChannels, send: Callable[[Message], None]) -> None:
        super().__init__(logging.DEBUG)
        self._channels = channels
        self._send = send

    def emit(self, record: logging.LogRecord) -> None:
        """Send one record (a record from another thread, or without a loop, is skipped)."""
        try:
            now = asyncio.get_running_loop().time()
        except RuntimeError:
            return
        try:
            text = record.getMessage()
        except (TypeError, ValueError):
            text = str(record.msg)
        level = log_level(record.levelno)
        message = self._channels.log(
            now, level, record.name, text, file=record.pathname, line=record.lineno
        )
        self._send(message)
