"""The executive's events: one frozen dataclass per kind, and their recorded form.

Every event has ``time`` (the loop time), ``action`` (the id of the action
concerned, if any) and ``name`` (the action's, monitor's or state key's name);
its class adds the facts of its kind as typed fields, and its ``kind`` is a
class attribute. `ExecEvent.data` gives those facts as a recording stores them
(the ``data`` object of a JSON Lines line or MCAP message), and `event_from_data`
reads them back: this module is the one place where events and their recorded
form meet, so that the recorders, the replay and the live view agree.

Reading is lenient, for recordings of older versions and files written by
hand: a fact that is missing or of the wrong type reads as its fallback
(None, False, 0, an empty tuple, "" or, for an outcome, ``not_done``), and a
resource event without ``leaves`` (written before compound resources came in)
takes its ``resources``. The module is long because it lists every kind: each
class is short.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Self

if TYPE_CHECKING:
    from collections.abc import Mapping


class EventKind(enum.StrEnum):
    """What happened in the executive; the value is the name used in recordings.

    Each kind has its class (`ExecEvent` lists them); ``event.kind`` is the
    kind of any event.
    """

    ACTION_SPAWNED = "action.spawned"
    ACTION_STARTED = "action.started"
    ACTION_FINISHED = "action.finished"
    CANCEL_REQUESTED = "action.cancel_requested"
    CANCEL_ESCALATED = "action.cancel_escalated"
    ACTION_ABANDONED = "action.abandoned"
    ACTION_PAUSED = "action.paused"
    ACTION_RESUMED = "action.resumed"
    RESOURCE_WAITING = "resource.waiting"
    RESOURCE_ACQUIRED = "resource.acquired"
    RESOURCE_RELEASED = "resource.released"
    RESOURCE_PREEMPTED = "resource.preempted"
    RESOURCE_SKIPPED = "resource.skipped"
    MONITOR_FIRED = "monitor.fired"
    STATE_SAMPLE = "state.sample"
    LOOP_BLOCKED = "loop.blocked"
    """The event loop did not turn for ``block_threshold`` or more (`LoopBlocked`)."""


class _Fields:
    """The recorded facts of one event, read leniently (see the module notes)."""

    __slots__ = ("_data",)

    def __init__(self, data: Mapping[str, object]) -> None:
        self._data = data

    def ident(self, key: str) -> int | None:
        value = self._data.get(key)
        return value if isinstance(value, int) and not isinstance(value, bool) else None

    def text(self, key: str, fallback: str = "") -> str:
        value = self._data.get(key)
        return value if isinstance(value, str) else fallback

    def optional_text(self, key: str) -> str | None:
        value = self._data.get(key)
        return value if isinstance(value, str) else None

    def number(self, key: str) -> float:
        value = self._data.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            return 0.0
        return float(value)

    def flag(self, key: str) -> bool:
        return bool(self._data.get(key))

    def names(self, key: str) -> tuple[str, ...]:
        value = self._data.get(key)
        return tuple(str(name) for name in value) if isinstance(value, list) else ()

    def value(self, key: str) -> object:
        return self._data.get(key)


_Head = tuple[float, int | None, str | None]
"""``(time, action, name)``: what every event has."""
_Cycle = tuple[tuple[int, str, int], ...]
"""A lock cycle: ``(waiter id, resource name, holder id)`` steps."""


@dataclass(frozen=True, slots=True)
class ExecEvent:
    """One executive event, stamped with the event loop's clock: the base of every kind's class.

    Actions: `ActionSpawned`, `ActionStarted`, `ActionFinished`, `CancelRequested`,
    `CancelEscalated`, `ActionAbandonment`, `ActionPaused`, `ActionResumed`.
    Resources (`ResourceEvent`): `ResourceWaiting`, `ResourceAcquired`,
    `ResourceReleased`, `ResourcePreempted`, `ResourceSkipped`. Then
    `MonitorFired`, `LoopBlocked`, and `StateSampled` (version 1 recordings).

    Attributes:
        kind: What happened (a class attribute: one class per kind).
        time: The loop time (``loop.time()``) at which it happened.
        action: The id of the action concerned, if any.
        name: The name of the action (or monitor, or state key) concerned.

    Examples:
        >>> event = ActionFinished(2.5, 1, "walk", outcome="succeeded", error=None)
        >>> event.kind.value, event.data
        ('action.finished', {'outcome': 'succeeded', 'error': None})
        >>> event_from_data(event.kind, 2.5, 1, "walk", event.data) == event
        True
    """

    kind: ClassVar[EventKind]
    time: float
    action: int | None
    name: str | None

    @property
    def data(self) -> dict[str, object]:
        """The facts of the kind as a recording stores them (JSON values: lists, not tuples).

        For writers of recordings; readers use the typed fields.
        """
        return {}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        """The event from its recorded facts (`event_from_data` picks the class)."""
        return cls(*head)


# -- actions ----------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ActionSpawned(ExecEvent):
    """An action was created (its body starts with `ActionStarted`).

    Attributes:
        parent: The id of the action that started it; None in the root scope.
    """

    kind: ClassVar[EventKind] = EventKind.ACTION_SPAWNED
    parent: int | None

    @property
    def data(self) -> dict[str, object]:
        return {"parent": self.parent}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.ident("parent"))


@dataclass(frozen=True, slots=True)
class ActionStarted(ExecEvent):
    """An action's body started."""

    kind: ClassVar[EventKind] = EventKind.ACTION_STARTED


@dataclass(frozen=True, slots=True)
class ActionFinished(ExecEvent):
    """An action is done.

    Attributes:
        outcome: How it ended, an `Outcome` value (``succeeded``, ``failed``,
            ``cancelled``, ``skipped``).
        error: The ``repr`` of its exception if it failed, else None.
    """

    kind: ClassVar[EventKind] = EventKind.ACTION_FINISHED
    outcome: str
    error: str | None

    @property
    def data(self) -> dict[str, object]:
        return {"outcome": self.outcome, "error": self.error}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.text("outcome", "not_done"), fields.optional_text("error"))


@dataclass(frozen=True, slots=True)
class CancelRequested(ExecEvent):
    """An action was asked to cancel (one event per action of a cancelled subtree).

    Attributes:
        reason: Why, if the canceller said.
        by: The id of the action that cancelled it; None from outside any action.
    """

    kind: ClassVar[EventKind] = EventKind.CANCEL_REQUESTED
    reason: str | None
    by: int | None

    @property
    def data(self) -> dict[str, object]:
        return {"reason": self.reason, "by": self.by}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.optional_text("reason"), fields.ident("by"))


@dataclass(frozen=True, slots=True)
class _Overrun(ExecEvent):
    """An action that overran its cancellation, and where it was."""

    location: str

    @property
    def data(self) -> dict[str, object]:
        return {"location": self.location}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.text("location"))


@dataclass(frozen=True, slots=True)
class CancelEscalated(_Overrun):
    """An action still ran a ``cancel_grace`` after its cancellation: cancelled again.

    Attributes:
        location: Where its body was (``file:line``, or ``an unknown place``).
    """

    kind: ClassVar[EventKind] = EventKind.CANCEL_ESCALATED


@dataclass(frozen=True, slots=True)
class ActionAbandonment(_Overrun):
    """An action ignored cancellation for two graces: its body is ended, and it is abandoned.

    (Not ``ActionAbandoned``: that is the exception thrown into the body.)

    Attributes:
        location: Where its body was (``file:line``, or ``an unknown place``).
    """

    kind: ClassVar[EventKind] = EventKind.ACTION_ABANDONED


@dataclass(frozen=True, slots=True)
class ActionPaused(ExecEvent):
    """An action froze: paused itself, or frozen with the subtree of a paused ancestor.

    Attributes:
        reason: Why, if the pauser said.
        by: The id of the action that paused it (a suspending reflex), if any.
        paused: The id of the action whose pause froze it: itself or an ancestor.
    """

    kind: ClassVar[EventKind] = EventKind.ACTION_PAUSED
    reason: str | None
    by: int | None
    paused: int | None

    @property
    def data(self) -> dict[str, object]:
        return {"reason": self.reason, "by": self.by, "paused": self.paused}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        reason, by, paused = (
            fields.optional_text("reason"),
            fields.ident("by"),
            fields.ident("paused"),
        )
        return cls(*head, reason, by, paused)


@dataclass(frozen=True, slots=True)
class ActionResumed(ExecEvent):
    """A frozen action thawed.

    Attributes:
        resumed: The id of the action whose resume thawed it: itself or an ancestor.
    """

    kind: ClassVar[EventKind] = EventKind.ACTION_RESUMED
    resumed: int | None

    @property
    def data(self) -> dict[str, object]:
        return {"resumed": self.resumed}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.ident("resumed"))


# -- resources --------------------------------------------------------------------------------

_Held = tuple[float, int | None, str | None, tuple[str, ...], tuple[str, ...], int]
"""What every resource event has: `_Head`, then ``resources``, ``leaves``, ``priority``."""


@dataclass(frozen=True, slots=True)
class ResourceEvent(ExecEvent):
    """The base of the resource events: one request (`lock`) of one action.

    Attributes:
        resources: The names of the resources asked for (compounds included).
        leaves: The names of the plain resources concerned: all the request's,
            or the one lent or given back (``preempt="suspend"``).
        priority: The request's priority.
    """

    resources: tuple[str, ...]
    leaves: tuple[str, ...]
    priority: int

    @property
    def data(self) -> dict[str, object]:
        return self._with_held({})

    def _with_held(self, facts: dict[str, object]) -> dict[str, object]:
        """``facts``, then those every resource event has (in the order recordings have)."""
        facts.setdefault("resources", list(self.resources))
        facts.setdefault("leaves", list(self.leaves))
        facts.setdefault("priority", self.priority)
        return facts

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*_held(head, fields))


def _held(head: _Head, fields: _Fields) -> _Held:
    resources = fields.names("resources")
    return (*head, resources, fields.names("leaves") or resources, fields.ident("priority") or 0)


@dataclass(frozen=True, slots=True)
class ResourceWaiting(ResourceEvent):
    """An action waits in line for resources."""

    kind: ClassVar[EventKind] = EventKind.RESOURCE_WAITING


@dataclass(frozen=True, slots=True)
class ResourceAcquired(ResourceEvent):
    """An action holds resources (granted, or a lent one given back).

    Attributes:
        given_back: A resource it had lent (``preempt="suspend"``) is its again.
    """

    kind: ClassVar[EventKind] = EventKind.RESOURCE_ACQUIRED
    given_back: bool = False

    @property
    def data(self) -> dict[str, object]:
        if self.given_back:
            return self._with_held({"leaves": list(self.leaves), "given_back": True})
        return self._with_held({})

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*_held(head, fields), fields.flag("given_back"))


@dataclass(frozen=True, slots=True)
class ResourceReleased(ResourceEvent):
    """An action let go of resources, left the line, or lent a resource.

    Attributes:
        withdrawn: It was waiting, and left the line (cancelled) before its turn.
        lent_to: The id of the action it lent ``leaves`` to (``preempt="suspend"``).
    """

    kind: ClassVar[EventKind] = EventKind.RESOURCE_RELEASED
    withdrawn: bool = False
    lent_to: int | None = None

    @property
    def data(self) -> dict[str, object]:
        if self.lent_to is not None:
            return self._with_held({"leaves": list(self.leaves), "lent_to": self.lent_to})
        return self._with_held({"withdrawn": True} if self.withdrawn else {})

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*_held(head, fields), fields.flag("withdrawn"), fields.ident("lent_to"))


@dataclass(frozen=True, slots=True)
class ResourcePreempted(ResourceEvent):
    """A higher-priority request took a resource of this action's: cancelled, or suspended.

    Attributes:
        resource: The plain resource it was preempted for.
        by: The id of the preempting action.
        reason: The cancel (or pause) reason given to it.
        suspended: It was paused and lent the resource (``preempt="suspend"``),
            not cancelled.
    """

    kind: ClassVar[EventKind] = EventKind.RESOURCE_PREEMPTED
    resource: str
    by: int | None
    reason: str
    suspended: bool = False

    @property
    def data(self) -> dict[str, object]:
        facts: dict[str, object] = {"resource": self.resource, "by": self.by, "reason": self.reason}
        if self.suspended:
            facts["suspended"] = True
        return self._with_held(facts)

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        by, reason, suspended = fields.ident("by"), fields.text("reason"), fields.flag("suspended")
        return cls(*_held(head, fields), fields.text("resource"), by, reason, suspended)


@dataclass(frozen=True, slots=True)
class ResourceSkipped(ResourceEvent):
    """A request was refused: busy and not allowed to wait, or closing a lock cycle.

    Attributes:
        busy: The plain resource in the way.
        holder: The id of the action holding it, if one does.
        queued: The id of the request queued ahead that would be served first, if any.
        deadlock: The lock cycle waiting would close (then ``queued`` is None).
    """

    kind: ClassVar[EventKind] = EventKind.RESOURCE_SKIPPED
    busy: str
    holder: int | None
    queued: int | None = None
    deadlock: _Cycle | None = None

    @property
    def data(self) -> dict[str, object]:
        facts: dict[str, object] = {"busy": self.busy, "holder": self.holder}
        if self.deadlock is None:
            facts["queued"] = self.queued
        else:
            facts["deadlock"] = [list(step) for step in self.deadlock]
        return self._with_held(facts)

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        busy, holder, queued = fields.text("busy"), fields.ident("holder"), fields.ident("queued")
        return cls(*_held(head, fields), busy, holder, queued, _cycle(fields.value("deadlock")))


def _cycle(value: object) -> _Cycle | None:
    if not isinstance(value, list):
        return None
    steps = []
    for step in value:
        match step:
            case [int(waiter), str(resource), int(holder)]:
                steps.append((waiter, resource, holder))
    return tuple(steps)


# -- the rest ---------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class MonitorFired(ExecEvent):
    """An event monitor fired (``name``: the monitor's; ``action``: None).

    Attributes:
        monitor: The monitor's id.
        var: What it watches: the state key, or the predicate's name.
        condition: Its condition as keywords (``becomes=True``).
        value: The value that fired it (its ``repr`` if not a JSON scalar).
        callback: What became of its callback: ``started``, ``dropped`` (the
            last run still busy) or ``none`` (no callback).
    """

    kind: ClassVar[EventKind] = EventKind.MONITOR_FIRED
    monitor: int | None
    var: str
    condition: str
    value: object
    callback: str

    @property
    def data(self) -> dict[str, object]:
        return {
            "monitor": self.monitor,
            "var": self.var,
            "condition": self.condition,
            "value": self.value,
            "callback": self.callback,
        }

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        monitor, var, value = fields.ident("monitor"), fields.text("var"), fields.value("value")
        return cls(*head, monitor, var, fields.text("condition"), value, fields.text("callback"))


@dataclass(frozen=True, slots=True)
class LoopBlocked(ExecEvent):
    """The event loop did not turn for ``block_threshold`` or more; emitted once it turns again.

    ``action``/``name``: the blocking action, if one.

    Attributes:
        duration: How long the loop stood still, in real seconds.
        threshold: The ``block_threshold`` it overran.
        blocker: Who blocked it, for people (``action crunch#1``, ``task 'main'``).
        location: The blocking ``file:line``, if known.
        stack: The blocking stack, formatted.
    """

    kind: ClassVar[EventKind] = EventKind.LOOP_BLOCKED
    duration: float
    threshold: float
    blocker: str
    location: str | None
    stack: str

    @property
    def data(self) -> dict[str, object]:
        return {
            "duration": self.duration,
            "threshold": self.threshold,
            "blocker": self.blocker,
            "location": self.location,
            "stack": self.stack,
        }

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        duration, threshold = fields.number("duration"), fields.number("threshold")
        blocker, location = fields.text("blocker"), fields.optional_text("location")
        return cls(*head, duration, threshold, blocker, location, fields.text("stack"))


@dataclass(frozen=True, slots=True)
class StateSampled(ExecEvent):
    """A state key's value (``name``: the key): version 1 recordings only.

    Recorders now write samples apart from the events; `load` turns these into samples.

    Attributes:
        value: The value written.
    """

    kind: ClassVar[EventKind] = EventKind.STATE_SAMPLE
    value: object

    @property
    def data(self) -> dict[str, object]:
        return {"value": self.value}

    @classmethod
    def _read(cls, head: _Head, fields: _Fields) -> Self:
        return cls(*head, fields.value("value"))


_TYPES: dict[EventKind, type[ExecEvent]] = {
    cls.kind: cls
    for cls in (
        ActionSpawned,
        ActionStarted,
        ActionFinished,
        CancelRequested,
        CancelEscalated,
        ActionAbandonment,
        ActionPaused,
        ActionResumed,
        ResourceWaiting,
        ResourceAcquired,
        ResourceReleased,
        ResourcePreempted,
        ResourceSkipped,
        MonitorFired,
        LoopBlocked,
        StateSampled,
    )
}


def event_type(kind: EventKind) -> type[ExecEvent]:
    """The class of the events of ``kind``.

    Examples:
        >>> event_type(EventKind.ACTION_SPAWNED).__name__
        'ActionSpawned'
    """
    return _TYPES[kind]


def event_from_data(
    kind: EventKind, time: float, action: int | None, name: str | None, data: Mapping[str, object]
) -> ExecEvent:
    """The event of ``kind`` from its recorded facts (``data``), read leniently (module notes)."""
    return _TYPES[kind]._read((time, action, name), _Fields(data))
