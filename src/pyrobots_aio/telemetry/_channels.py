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
``/pyrobots/arena``         ``foxglove.SceneUpdate``     the walls, obstacles and dock
=========================== ============================ =====================================

Every message is JSON (``json`` encoding, ``jsonschema`` schemas), strict: a
non-finite float is written as null. Foxglove recognises its well-known
schemas by name, whatever the encoding. Message times are the run's wall-clock
start plus the loop time elapsed since (so Foxglove shows the date of the
run); the events and state samples also carry a time in seconds in their
``time`` field: the loop time in a recording (whose header's ``t0`` is the
start), the seconds since the start in the live view (whose loop time may be
the machine's monotonic clock, meaningless to a viewer).
"""

from __future__ import annotations

import asyncio
import logging
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
from .._core._json import strict_json
from . import _wellknown as wk
from ._arena import ARENA, SCENE_UPDATE, SCENE_UPDATE_SCHEMA, scene_update

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping

    from .._core._events import ExecEvent
    from ..poses import Pose2D

__all__ = [
    "ACTIONS",
    "ARENA",
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
    "SCENE_UPDATE",
    "SCHEMAS",
    "STATE_PREFIX",
    "TF",
    "FoxgloveChannels",
    "LogForwarder",
    "Message",
    "log_level",
]

ACTIONS, RESOURCES, MONITORS = "/pyrobots/actions", "/pyrobots/resources", "/pyrobots/monitors"
STATE_PREFIX = "/pyrobots/state/"
POSE, TF, LOG = "/pyrobots/pose", "/tf", "/pyrobots/log"
MAP = "map"
EVENT = "pyrobots_aio.ExecEvent"
"""The schema of the executive's events (``/pyrobots/actions``, ``resources``, ``monitors``)."""
SAMPLE = "pyrobots_aio.StateSample"
"""The schema of a state key's values (``/pyrobots/state/<key>``)."""
POSE_IN_FRAME = "foxglove.PoseInFrame"
"""Foxglove's well-known schema of the robot's pose (``/pyrobots/pose``)."""
FRAME_TRANSFORMS, FOXGLOVE_LOG = "foxglove.FrameTransforms", "foxglove.Log"

_TRANSFORM = {
    "title": "foxglove.FrameTransform",
    "type": "object",
    "properties": {
        "timestamp": wk.TIME,
        "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"},
        "translation": wk.VECTOR3,
        "rotation": wk.QUATERNION,
    },
    "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"],
}
_LEVELS = ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL")

SCHEMAS: dict[str, dict[str, Any]] = {
    EVENT: {
        "title": EVENT,
        "type": "object",
        "properties": {
            "time": {
                "type": "number",
                "description": "seconds: loop time (a recording), since the start (live)",
            },
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
            "time": {
                "type": "number",
                "description": "seconds: loop time (a recording), since the start (live)",
            },
            "key": {"type": "string"},
            "value": {"description": "the value written"},
        },
        "required": ["time", "key", "value"],
    },
    POSE_IN_FRAME: {
        "title": POSE_IN_FRAME,
        "type": "object",
        "properties": {
            "timestamp": wk.TIME,
            "frame_id": {"type": "string"},
            "pose": wk.POSE,
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
            "timestamp": wk.TIME,
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
    SCENE_UPDATE: SCENE_UPDATE_SCHEMA,
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


class FoxgloveChannels:
    """Turns a run's events, samples and log lines into `Message` values.

    Args:
        origin_ns: The wall-clock time of the run's start, in ns since 1970.
        t0: The loop time at that start.
        frame: The robot frame whose pose is published (``base_link``).
        since_start: The ``time`` of events and samples counts seconds from
            ``t0`` (the live view); else it is the loop time (a recording).
    """

    def __init__(
        self, origin_ns: int, t0: float, frame: str = "base_link", *, since_start: bool = False
    ) -> None:
        self.origin_ns = origin_ns
        self.t0 = t0
        self.frame = frame
        self.since_start = since_start
        self._names: dict[int, str] = {}

    def stamp(self, time: float) -> int:
        """The message time of loop time ``time`` (never before the start)."""
        return self.origin_ns + max(0, round((time - self.t0) * 1e9))

    def _seconds(self, time: float) -> float:
        """The ``time`` field of loop time ``time``."""
        return time - self.t0 if self.since_start else time

    def event(self, event: ExecEvent) -> list[Message]:
        """The executive event on its channel, and a log line if it is a notable one."""
        kind = event.kind.value
        topic = _GROUP_TOPICS.get(kind.partition(".")[0], MONITORS)
        body = {"time": self._seconds(event.time), "kind": kind, "action": event.action}
        body.update(name=event.name, data=event.data)
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
        stamp, seconds = self.stamp(time), self._seconds(time)
        messages = [
            Message(
                STATE_PREFIX + key,
                SAMPLE,
                strict_json({"time": seconds, "key": key, "value": value}),
                stamp,
            )
            for key, value in values.items()
        ]
        if pose is not None:
            x, y, yaw = pose
            planar = wk.planar_pose(x, y, 0.0, yaw)
            in_frame = {"timestamp": wk.stamp(stamp), "frame_id": MAP, "pose": planar}
            transform = {"timestamp": wk.stamp(stamp), "parent_frame_id": MAP}
            transform.update(child_frame_id=self.frame, translation=planar["position"])
            transform["rotation"] = planar["orientation"]
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
        body = {"timestamp": wk.stamp(stamp), "level": level, "message": text, "name": name}
        body.update(file=file, line=max(0, line))
        return Message(LOG, FOXGLOVE_LOG, strict_json(body), stamp)

    def arena(self, plan: Iterable[object], log_time: int | None = None) -> Message:
        """The ``foxglove.SceneUpdate`` drawing a floor plan, at ``log_time`` (None: the start)."""
        stamp = self.origin_ns if log_time is None else log_time
        return Message(ARENA, SCENE_UPDATE, strict_json(scene_update(plan, stamp)), stamp)


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
