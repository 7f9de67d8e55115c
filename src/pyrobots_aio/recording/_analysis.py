"""From a recording's events to intervals: action spans, pauses, resource holds and waits.

Both the summary and the timeline read a recording through `analyse`, one
pass over the events in the order they happened. Times stay in loop time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from pyrobots_aio import (
    ActionAbandonment,
    ActionFinished,
    ActionPaused,
    ActionResumed,
    ActionSpawned,
    ActionStarted,
    CancelEscalated,
    CancelRequested,
    MonitorFired,
    ResourceAcquired,
    ResourceEvent,
    ResourcePreempted,
    ResourceReleased,
    ResourceWaiting,
    StateSampled,
)

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
    preemptions: list[ResourcePreempted] = field(default_factory=list)
    firings: list[MonitorFired] = field(default_factory=list)
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


def _span(found: Analysis, event: ExecEvent) -> Span:
    ident = event.action if event.action is not None else -1
    span = found.spans.get(ident)
    if span is None:  # a recording that began while the action already ran
        span = found.spans[ident] = Span(ident, event.name or "?", None, event.time)
    return span


def _on_spawned(found: Analysis, event: ActionSpawned) -> None:
    ident, parent = event.action if event.action is not None else -1, event.parent
    span = found.spans[ident] = Span(ident, event.name or "?", parent, event.time)
    above = found.spans.get(parent) if parent is not None else None
    frozen = above.paused if above is not None else None
    if frozen is not None:  # started by a frozen action: it starts frozen (no event says so)
        span.pauses.append(Pause(event.time, frozen.reason, frozen.by, frozen.root))
    found._running += 1
    if found._running > found.peak:
        found.peak, found.peak_time = found._running, event.time


def _on_action(found: Analysis, event: ExecEvent) -> None:
    if isinstance(event, ActionSpawned):
        _on_spawned(found, event)
        return
    span = _span(found, event)
    match event:
        case ActionStarted():
            span.started = event.time
        case ActionFinished(outcome=outcome, error=error):
            span.finished, span.outcome, span.error = event.time, outcome, error
            span.thaw(event.time, "finished")
            found._running -= 1
        case CancelRequested(reason=reason, by=by):
            span.thaw(event.time, "cancelled")
            if span.cancelled_at is None:
                span.cancelled_at, span.reason, span.by = event.time, reason, by
        case ActionPaused(reason=reason, by=by, paused=root) if span.paused is None:
            span.pauses.append(Pause(event.time, reason, by, root))
        case ActionResumed():
            span.thaw(event.time, "resumed")
        case CancelEscalated():
            found.escalations += 1
        case ActionAbandonment():
            found.abandoned += 1


def _on_resource(found: Analysis, event: ResourceEvent) -> None:
    ident, name = event.action if event.action is not None else -1, event.name or "?"
    time, priority = event.time, event.priority
    for leaf in event.leaves:
        key = (ident, leaf)
        match event:
            case ResourceWaiting():
                wait = Interval(leaf, ident, name, time, priority=priority, outcome=NOT_DONE)
                found._open_waits[key] = wait
                found.waits.append(wait)
            case ResourceAcquired():
                _close_wait(found, key, time, "acquired")
                hold = Interval(leaf, ident, name, time, priority=priority)
                found._open_holds[key] = hold
                found.holds.append(hold)
            case ResourceReleased(withdrawn=True):
                _close_wait(found, key, time, "withdrawn")
            case ResourceReleased():
                released = found._open_holds.pop(key, None)
                if released is not None:
                    released.end = time
    if isinstance(event, ResourcePreempted):
        found.preemptions.append(event)
        victim = found.spans.get(ident)
        if victim is not None and victim.via is None:
            victim.via = event.resource or None


def _close_wait(found: Analysis, key: tuple[int, str], time: float, outcome: str) -> None:
    wait = found._open_waits.pop(key, None)
    if wait is not None:
        wait.end, wait.outcome = time, outcome


def analyse(recording: Recording) -> Analysis:
    """Read the spans, holds, waits, preemptions and firings of ``recording``."""
    found = Analysis()
    for event in recording.events:
        if isinstance(event, ResourceEvent):
            _on_resource(found, event)
        elif isinstance(event, MonitorFired):
            found.firings.append(event)
        elif isinstance(event, StateSampled):
            found.samples += 1
        elif event.kind.value.startswith("action."):
            _on_action(found, event)
    return found


@dataclass(slots=True)
class ResourceUse:
    """What happened to one plain resource: its holds, waits and preemptions, in order."""

    holds: list[Interval] = field(default_factory=list)
    waits: list[Interval] = field(default_factory=list)
    preemptions: list[ResourcePreempted] = field(default_factory=list)


def by_resource(found: Analysis) -> dict[str, ResourceUse]:
    """The use of each resource held or waited for, names sorted (one pass over each list)."""
    uses: dict[str, ResourceUse] = {}
    for interval in found.holds:
        _use(uses, interval.resource).holds.append(interval)
    for interval in found.waits:
        _use(uses, interval.resource).waits.append(interval)
    for event in found.preemptions:
        if (use := uses.get(event.resource)) is not None:
            use.preemptions.append(event)
    return dict(sorted(uses.items()))


def _use(uses: dict[str, ResourceUse], name: str) -> ResourceUse:
    use = uses.get(name)
    if use is None:
        use = uses[name] = ResourceUse()
    return use


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
