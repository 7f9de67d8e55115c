"""Instrumentation: every executive event, fanned out to registered instruments.

Recorders (JSON Lines, MCAP) and tests plug in here. Emitting costs one truth
test when no instrument is registered, so the hot paths guard with
``if instruments:`` before building an event.
"""

from __future__ import annotations

import enum
import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, runtime_checkable

if TYPE_CHECKING:
    from collections.abc import Iterator, Mapping

_log = logging.getLogger("pyrobots_aio.instrument")


class EventKind(enum.StrEnum):
    """What happened in the executive; the value is the name used in recordings."""

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
    """The event loop did not turn for ``block_threshold`` or more; emitted once it turns
    again. ``action``/``name``: the blocking action, if one; ``data``: ``duration`` (real
    seconds), ``threshold``, ``blocker``, ``location`` (``file:line``) and ``stack``."""


@dataclass(frozen=True, slots=True)
class ExecEvent:
    """One executive event, stamped with the event loop's clock.

    Attributes:
        kind: What happened.
        time: The loop time (``loop.time()``) at which it happened.
        action: The id of the action concerned, if any.
        name: The name of the action (or monitor, or state key) concerned.
        data: Kind-specific details (``parent``, ``outcome``, ``reason``, ``by``,
            ``resource``, ``value`` ...), JSON-friendly values only.
    """

    kind: EventKind
    time: float
    action: int | None = None
    name: str | None = None
    data: Mapping[str, object] = field(default_factory=dict)


@runtime_checkable
class Instrument(Protocol):
    """Receives every executive event of the robot it is attached to.

    ``on_event`` runs synchronously inside the executive: keep it fast and never
    block (buffer and write in bulk, as the recorders do).
    """

    def on_event(self, event: ExecEvent) -> None:
        """Handle one event."""


class Instruments:
    """The instruments attached to one robot.

    Example:
        >>> hub = Instruments()
        >>> class Count:
        ...     n = 0
        ...     def on_event(self, event: ExecEvent) -> None:
        ...         self.n += 1
        >>> counter = Count()
        >>> hub.add(counter)
        >>> hub.emit(ExecEvent(EventKind.ACTION_STARTED, 0.0, 1, "walk"))
        >>> counter.n
        1
    """

    __slots__ = ("items",)

    def __init__(self) -> None:
        self.items: tuple[Instrument, ...] = ()
        """The instruments, in the order added (empty: hot paths skip building events)."""

    def add(self, instrument: Instrument) -> None:
        """Attach an instrument (an object with ``on_event(event)``)."""
        if not callable(getattr(instrument, "on_event", None)):
            msg = f"{instrument!r} is not an instrument: it needs an on_event(event) method"
            raise TypeError(msg)
        self.items = (*self.items, instrument)

    def remove(self, instrument: Instrument) -> None:
        """Detach an instrument; detaching one that is not attached does nothing."""
        self.items = tuple(i for i in self.items if i is not instrument)

    def __bool__(self) -> bool:
        return bool(self.items)

    def __iter__(self) -> Iterator[Instrument]:
        return iter(self.items)

    def emit(self, event: ExecEvent) -> None:
        """Send one event to every instrument; a failing instrument is logged, not fatal."""
        for instrument in self.items:
            try:
                instrument.on_event(event)
            except Exception:
                _log.exception("instrument %r failed on %s", instrument, event.kind)

    def __repr__(self) -> str:
        return f"<Instruments {list(self.items)!r}>"
