"""From a recording's events to intervals: action spans, pauses, resource holds and waits.

Both the summary and the timeline read a recording through `analyse`, one
pass over the events in the order they happened. Times stay in loop time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from pyrobots_aio import EventKind

if TYPE_CHECKING:
    from pyrobots_aio import ExecEvent

    from ._recording import Recording

NOT_DONE = "not_done"
STILL_PAUSED = "still paused"


@dataclass(slots=True)
class Pause:
    """A spell an action spent frozen: paused, until it was resumed, cancelled or done.

    ``root`` is the action whose pause froze it: itself, or an ancestor (a
    pause freezes the whole subtree). ``ended`` says how the spell ended:
    ``resumed``, ``cancelled`` (cancellation thaws a paused action at once),
    ``finished``, or `STILL_PAUSED` when the recording stopped first (then
    ``end`` is None).
    """

    start: float
    reason: str | None = None
    by: int | None = None
    root: int | None = None
    end: float | None = None
    ended: str = STILL_PAUSED


@dataclass(slots=True)
class Span:
    """One action, from spawn to finish."""

    id: int
    name: str
    parent: int | None
    spawned: float
    started: float | None = None
    finished: float | None = None
    outcome: str = NOT_DONE
    error: str | None = None
    reason: str | None = None
    by: int | None = None
    via: str | None = None
    """The resource it was preempted for, if any."""
    cancelled_at: float | None = None
    pauses: list[Pause] = field(default_factory=list)
    """Its frozen spells, in order (at most the last one still open)."""

    @property
    def begin(self) -> float:
        """When its body started (or when it was spawned, if it never started)."""
        return self.started if self.started is not None else self.spawned

    @property
    def paused(self) -> Pause | None:
        """The spell it is frozen in at this point of the recording, if any."""
        last = self.pauses[-1] if self.pauses else None
        return last if last is not None and last.end is None else None

    def thaw(self, time: float, ended: str) -> None:
        """End the spell it is frozen in, if any, at ``time``."""
        spell = self.paused
        if spell is not None:
            spell.end, spell.ended = time, ended


@dataclass(slots=True)
class Interval:
    """A resource held or waited for by one action, on one plain resource."""

    resource: str
    action: int
    name: str
    start: float
    end: float | None = None
    priority: int = 0
    outcome: str = "held"
    """For waits: ``acquired``, ``withdrawn`` or ``not_done``; ``held`` for holds."""


@dataclass(slots=True)
class Analysis:
    """Everything `analyse` finds in a recording."""

    spans: dict[int, Span] = field(default_factory=dict)
    holds: list[Interval] = field(default_factory=list)
    waits: list[Interval] = field(default_factory=list)
    preemptions: list[ExecEvent] = field(default_factory=list)
    firings: list[ExecEvent] = field(default_factory=list)
    peak: int = 0
    peak_time: float | None = None
    samples: int = 0
    escalations: int = 0
    abandoned: int = 0
    _open_holds: dict[tuple[int, str], Interval] = field(default_factory=dict)
    _open_waits: dict[tuple[int, str], Interval] = field(default_factory=dict)
    _running: int = 0

    def label(self, ident: int | None) -> str | None:
        """``name#id`` of an action, or None."""
        if ident is None:
            return None
        span = self.spans.get(ident)
        return f"{span.name}#{ident}" if span is not None else f"#{ident}"


def _leaves(event: ExecEvent) -> list[str]:
    leaves = event.data.get("leaves") or event.data.get("resources") or []
    return [str(leaf) for leaf in leaves] if isinstance(leaves, list) else []


def _int(value: object) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _str(value: object) -> str | None:
    return value if isinstance(value, str) else None


def _span(found: Analysis, event: ExecEvent) -> Span:
    ident = event.action if event.action is not None else -1
    span = found.spans.get(ident)
    if span is None:  # a recording that began while the action already ran
        span = found.spans[ident] = Span(ident, event.name or "?", None, event.time)
    return span


def _on_action(found: Analysis, event: ExecEvent) -> None:
    kind = event.kind
    if kind is EventKind.ACTION_SPAWNED:
        ident = event.action if event.action is not None else -1
        parent = _int(event.data.get("parent"))
        span = found.spans[ident] = Span(ident, event.name or "?", parent, event.time)
        above = found.spans.get(parent) if parent is not None else None
        frozen = above.paused if above is not None else None
        if frozen is not None:  # started by a frozen action: it starts frozen (no event says so)
            span.pauses.append(Pause(event.time, frozen.reason, frozen.by, frozen.root))
        found._running += 1
        if found._running > found.peak:
            found.peak, found.peak_time = found._running, event.time
        return
    span = _span(found, event)
    if kind is EventKind.ACTION_STARTED:
        span.started = event.time
    elif kind is EventKind.ACTION_FINISHED:
        span.finished = event.time
        span.outcome = _str(event.data.get("outcome")) or NOT_DONE
        span.error = _str(event.data.get("error"))
        span.thaw(event.time, "finished")
        found._running -= 1
    elif kind is EventKind.CANCEL_REQUESTED:
        span.thaw(event.time, "cancelled")
        if span.cancelled_at is None:
            span.cancelled_at = event.time
            span.reason = _str(event.data.get("reason"))
            span.by = _int(event.data.get("by"))
    elif kind is EventKind.ACTION_PAUSED and span.paused is None:
        data = event.data
        root = _int(data.get("paused"))
        span.pauses.append(Pause(event.time, _str(data.get("reason")), _int(data.get("by")), root))
    elif kind is EventKind.ACTION_RESUMED:
        span.thaw(event.time, "resumed")
    elif kind is EventKind.CANCEL_ESCALATED:
        found.escalations += 1
    elif kind is EventKind.ACTION_ABANDONED:
        found.abandoned += 1


def _on_resource(found: Analysis, event: ExecEvent) -> None:
    kind, ident = event.kind, event.action if event.action is not None else -1
    name = event.name or "?"
    priority = _int(event.data.get("priority")) or 0
    for leaf in _leaves(event):
        key = (ident, leaf)
        if kind is EventKind.RESOURCE_WAITING:
            wait = Interval(leaf, ident, name, event.time, priority=priority, outcome=NOT_DONE)
            found._open_waits[key] = wait
            found.waits.append(wait)
        elif kind is EventKind.RESOURCE_ACQUIRED:
            _close_wait(found, key, event.time, "acquired")
            hold = Interval(leaf, ident, name, event.time, priority=priority)
            found._open_holds[key] = hold
            found.holds.append(hold)
        elif kind is EventKind.RESOURCE_RELEASED:
            if event.data.get("withdrawn"):
                _close_wait(found, key, event.time, "withdrawn")
            else:
                released = found._open_holds.pop(key, None)
                if released is not None:
                    released.end = event.time
    if kind is EventKind.RESOURCE_PREEMPTED:
        found.preemptions.append(event)
        victim = found.spans.get(ident)
        if victim is not None and victim.via is None:
            victim.via = _str(event.data.get("resource"))


def _close_wait(found: Analysis, key: tuple[int, str], time: float, outcome: str) -> None:
    wait = found._open_waits.pop(key, None)
    if wait is not None:
        wait.end, wait.outcome = time, outcome


def analyse(recording: Recording) -> Analysis:
    """Read the spans, holds, waits, preemptions and firings of ``recording``."""
    found = Analysis()
    for event in recording.events:
        group = event.kind.value.partition(".")[0]
        if group == "action":
            _on_action(found, event)
        elif group == "resource":
            _on_resource(found, event)
        elif event.kind is EventKind.MONITOR_FIRED:
            found.firings.append(event)
        elif event.kind is EventKind.STATE_SAMPLE:
            found.samples += 1
    return found


def held_time(holds: list[Interval], stop: float) -> float:
    """Seconds during which at least one of ``holds`` (of one resource) was held."""
    edges = sorted(
        [(h.start, 1) for h in holds] + [(h.end if h.end is not None else stop, -1) for h in holds]
    )
    total, depth, since = 0.0, 0, 0.0
    for time, step in edges:
        if depth == 0 and step == 1:
            since = time
        depth += step
        if depth == 0:
            total += time - since
    return total
