"""`summarize`: the numbers of a recorded run, as frozen values.

Conventions: times in a `Summary` are seconds since the recording's start;
"per minute" series count what happened in each minute of the run (the last
minute may be partial); their means are totals divided by the run's length in
minutes. "Actions" are spawned actions; "events" are monitor firings (pyRobots'
events: what ``robot.whenever``/``robot.on`` watch for).
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ._analysis import NOT_DONE, Analysis, Span, analyse, by_resource, held_time

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

    from ._recording import Recording

MINUTE = 60.0


@dataclass(frozen=True, slots=True)
class Outcomes:
    """How many actions ended each way (``not_done``: still running when recording stopped)."""

    succeeded: int = 0
    failed: int = 0
    cancelled: int = 0
    skipped: int = 0
    not_done: int = 0

    @property
    def total(self) -> int:
        """All of them."""
        return self.succeeded + self.failed + self.cancelled + self.skipped + self.not_done

    @classmethod
    def count(cls, outcomes: Iterable[str]) -> Outcomes:
        """Count outcome values (``"succeeded"`` ...); unknown values count as not done."""
        seen = Counter(outcomes)
        known = {name: seen.pop(name, 0) for name in cls.__dataclass_fields__}
        known[NOT_DONE] += sum(seen.values())
        return cls(**known)


@dataclass(frozen=True, slots=True)
class ActionStats:
    """Counts and durations of one action (by name).

    Durations run from the body's start (``action.started``) to the action
    being done, over the actions that finished (None if none did): cleanup and
    children are included, and so is any wait for a resource, since an
    action's ``@lock`` is taken once its body has started.
    """

    name: str
    count: int
    outcomes: Outcomes
    min_duration: float | None
    median_duration: float | None
    max_duration: float | None


@dataclass(frozen=True, slots=True)
class ResourceStats:
    """How one plain resource was used.

    Attributes:
        name: The resource.
        held: Seconds it was held (by anyone).
        utilisation: ``held`` as a fraction of the recording's duration.
        acquisitions: Times it was granted.
        waits: Requests that had to wait for it.
        max_wait: The longest of those waits, in seconds.
        preemptions: Holders cancelled to hand it over.
    """

    name: str
    held: float
    utilisation: float
    acquisitions: int
    waits: int
    max_wait: float
    preemptions: int


@dataclass(frozen=True, slots=True)
class Cancellation:
    """One cancellation request: who was cancelled, when, by whom, why.

    Attributes:
        time: Seconds since the start.
        action: The cancelled action's id.
        name: Its name.
        reason: The reason given, if any.
        by: The id of the action that asked, None if it came from outside any action.
        by_name: That action's ``name#id``.
        resource: The resource it was preempted for, if it was preempted.
    """

    time: float
    action: int
    name: str
    reason: str | None
    by: int | None
    by_name: str | None
    resource: str | None = None

    def describe(self) -> str:
        """One line: ``move#7 cancelled by bumper_reflex#12: preempted ...``."""
        who = f" by {self.by_name}" if self.by_name else ""
        why = f": {self.reason}" if self.reason else ""
        return f"{self.name}#{self.action} cancelled{who}{why}"


@dataclass(frozen=True, slots=True)
class Failure:
    """An action that failed, and the error (its ``repr``)."""

    time: float
    action: int
    name: str
    error: str | None


@dataclass(frozen=True, slots=True)
class Summary:
    """The numbers of a recorded run (see the module notes for the conventions).

    Attributes:
        robot: The robot class recorded, if known.
        seed: Its seed, if known.
        duration: Seconds recorded.
        complete: Whether the recording was closed properly and read without error.
        records: Executive events in the recording (state samples and poses not included).
        actions: Actions spawned.
        outcomes: How they ended.
        actions_per_minute: Actions spawned in each minute of the run (at most
            `MAX_BUCKETS` minutes: the last one counts the rest).
        mean_actions_per_minute: ``actions`` over the duration in minutes.
        events_per_minute: Monitor firings in each minute of the run.
        mean_events_per_minute: Firings over the duration in minutes.
        peak_concurrency: Most actions alive at once (spawned, not yet done).
        peak_time: When that peak was first reached (seconds since the start).
        per_action: Counts, outcomes and durations by action name, sorted by name.
        resources: Use of each plain resource, sorted by name.
        cancellations: Every cancellation request, in order.
        failures: Every failed action, in order.
        monitor_firings: Firings per monitor name.
        state_samples: State values recorded (every key).
        poses: Poses recorded.
        escalations: Cancellations repeated after an action overran its grace.
        abandoned: Actions abandoned after ignoring cancellation.
        pauses: Times an action was paused (``handle.pause``, ``robot.pause_all``: one
            per action paused; the descendants frozen with it are not counted again).
        paused_time: Seconds those actions spent paused, added up (a pause still on
            when the recording stopped counts until then).
        frozen_actions: Actions that spent any time frozen, paused themselves or
            under a paused ancestor.
    """

    robot: str | None
    seed: int | None
    duration: float
    complete: bool
    records: int
    actions: int
    outcomes: Outcomes
    actions_per_minute: tuple[int, ...]
    mean_actions_per_minute: float
    events_per_minute: tuple[int, ...]
    mean_events_per_minute: float
    peak_concurrency: int
    peak_time: float | None
    per_action: tuple[ActionStats, ...]
    resources: tuple[ResourceStats, ...]
    cancellations: tuple[Cancellation, ...]
    failures: tuple[Failure, ...]
    monitor_firings: Mapping[str, int] = field(default_factory=dict)
    state_samples: int = 0
    poses: int = 0
    escalations: int = 0
    abandoned: int = 0
    pauses: int = 0
    paused_time: float = 0.0
    frozen_actions: int = 0


MAX_BUCKETS = 10_000
"""Most buckets a series holds (a week of minutes): memory follows the events, not the span."""


def per_bucket(times: Iterable[float], start: float, duration: float, width: float) -> list[int]:
    """Count ``times`` in consecutive buckets of ``width`` seconds from ``start``.

    At most `MAX_BUCKETS` buckets: times past the last one are counted in it.
    """
    buckets = duration / width if width > 0 else 0.0
    counts = [0] * (min(MAX_BUCKETS, max(1, math.ceil(buckets))) if math.isfinite(buckets) else 1)
    last = len(counts) - 1
    for time in times:
        index = (time - start) // width if width > 0 else 0.0
        counts[int(min(last, max(0.0, index))) if math.isfinite(index) else last] += 1
    return counts


def _rate(total: int, duration: float) -> float:
    return total * MINUTE / duration if duration > 0 else float(total)


def _action_stats(name: str, spans: list[Span]) -> ActionStats:
    durations = sorted(s.finished - s.begin for s in spans if s.finished is not None)
    return ActionStats(
        name,
        len(spans),
        Outcomes.count(s.outcome for s in spans),
        durations[0] if durations else None,
        statistics.median(durations) if durations else None,
        durations[-1] if durations else None,
    )


def _resource_stats(found: Analysis, recording: Recording) -> list[ResourceStats]:
    duration, stop = recording.duration, recording.stop
    stats = []
    for name, use in by_resource(found).items():
        held = held_time(use.holds, stop)
        waits = use.waits
        longest = max(((w.end if w.end is not None else stop) - w.start for w in waits), default=0)
        share = held / duration if duration > 0 else 0.0
        stats.append(
            ResourceStats(
                name, held, share, len(use.holds), len(waits), longest, len(use.preemptions)
            )
        )
    return stats


def _cancellations(found: Analysis, start: float) -> list[Cancellation]:
    cancels = [
        Cancellation(at - start, s.id, s.name, s.reason, s.by, found.label(s.by), s.via)
        for s in found.spans.values()
        if (at := s.cancelled_at) is not None
    ]
    return sorted(cancels, key=lambda c: (c.time, c.action))


def _paused(spans: Iterable[Span], stop: float) -> tuple[int, float, int]:
    """Pauses (of the actions paused themselves), their seconds, and the actions frozen."""
    direct = [
        (p.end if p.end is not None else stop) - p.start
        for s in spans
        for p in s.pauses
        if p.root in {None, s.id}
    ]
    return len(direct), math.fsum(direct), sum(1 for s in spans if s.pauses)


def summarize(recording: Recording) -> Summary:
    """Compute the `Summary` of a recording.

    Examples:
        >>> from pyrobots_aio.recording import load, summarize
        >>> summary = summarize(load("run.jsonl"))  # doctest: +SKIP
        >>> summary.peak_concurrency, summary.mean_actions_per_minute  # doctest: +SKIP
        (4, 87.5)
    """
    found = analyse(recording)
    start, duration = recording.start, recording.duration
    spans = sorted(found.spans.values(), key=lambda s: s.id)
    by_name: dict[str, list[Span]] = {}
    for span in spans:
        by_name.setdefault(span.name, []).append(span)
    firings = Counter(e.name or "?" for e in found.firings)
    failures = [
        Failure(at - start, s.id, s.name, s.error)
        for s in spans
        if s.outcome == "failed" and (at := s.finished) is not None
    ]
    header = recording.header
    pauses, paused_time, frozen = _paused(spans, recording.stop)
    return Summary(
        robot=header.robot,
        seed=header.seed,
        duration=duration,
        complete=recording.complete,
        records=len(recording.events),
        actions=len(spans),
        outcomes=Outcomes.count(s.outcome for s in spans),
        actions_per_minute=tuple(per_bucket((s.spawned for s in spans), start, duration, MINUTE)),
        mean_actions_per_minute=_rate(len(spans), duration),
        events_per_minute=tuple(
            per_bucket((e.time for e in found.firings), start, duration, MINUTE)
        ),
        mean_events_per_minute=_rate(len(found.firings), duration),
        peak_concurrency=found.peak,
        peak_time=None if found.peak_time is None else found.peak_time - start,
        per_action=tuple(_action_stats(n, by_name[n]) for n in sorted(by_name)),
        resources=tuple(_resource_stats(found, recording)),
        cancellations=tuple(_cancellations(found, start)),
        failures=tuple(failures),
        monitor_firings=dict(sorted(firings.items())),
        state_samples=recording.state_samples,
        poses=len(recording.poses),
        escalations=found.escalations,
        abandoned=found.abandoned,
        pauses=pauses,
        paused_time=paused_time,
        frozen_actions=frozen,
    )
