"""`format_summary`: a `Summary` as a plain-text report, tables aligned."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ._summary import Summary

_SHOWN = 20  # list items shown before "... and N more"
DURATIONS = "  (durations: from action.started to done, waits for resources included)"
"""The note under the per-action table: a body starts before its ``@lock`` waits."""


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


_CONTROLS = {c: f"\\x{c:02x}" for c in [*range(0x20), *range(0x7F, 0xA0)]}
_CONTROLS.update({0x2028: "\\u2028", 0x2029: "\\u2029"})
_CONTROLS.update({c: f"\\u{c:04x}" for c in range(0xD800, 0xE000)})  # lone surrogates


def shown(text: object) -> str:
    r"""``text`` safe for a terminal: control characters (escape sequences, newlines) escaped.

    Every string taken from a recording goes through this, so that a crafted
    recording cannot move the cursor, recolour the terminal or forge lines;
    lone surrogates (``"\ud800"``, valid JSON but no text) are escaped too,
    since they cannot be written out as UTF-8.

    Examples:
        >>> shown("drive\x1b[2J")
        'drive\\x1b[2J'
    """
    return str(text).translate(_CONTROLS)


def _series(counts: Sequence[int], duration: float) -> str:
    minutes = max(1, math.ceil(duration / 60)) if math.isfinite(duration) else len(counts)
    more = f", ... ({minutes:g} minutes)" if minutes > _SHOWN else ""
    return ", ".join(str(c) for c in counts[:_SHOWN]) + more


def table(header: Sequence[str], rows: Sequence[Sequence[str]], indent: str = "  ") -> list[str]:
    """Align ``rows`` under ``header``: the first column left, the others right."""
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]

    def line(row: Sequence[str]) -> str:
        cells = [row[0].ljust(widths[0])] + [
            c.rjust(w) for c, w in zip(row[1:], widths[1:], strict=True)
        ]
        return (indent + "  ".join(cells)).rstrip()

    return [line(header)] + [line(row) for row in rows]


def _overview(summary: Summary) -> list[str]:
    robot = shown(summary.robot or "unknown robot")
    seed = f", seed {summary.seed}" if summary.seed is not None else ""
    state = "closed cleanly" if summary.complete else "NOT closed (incomplete)"
    o = summary.outcomes
    peak_at = f" at {summary.peak_time:.3f} s" if summary.peak_time is not None else ""
    sampled = ""
    if summary.state_samples or summary.poses:
        sampled = f" ({summary.state_samples} state samples, {summary.poses} poses)"
    lines = [
        f"{robot}{seed}: {summary.duration:.3f} s recorded, {summary.records} events{sampled}, "
        f"{state}",
        f"  actions            {summary.actions}: {o.succeeded} succeeded, {o.failed} failed, "
        f"{o.cancelled} cancelled, {o.skipped} skipped, {o.not_done} not done",
        f"  actions per minute {summary.mean_actions_per_minute:.1f} mean; "
        f"by minute: {_series(summary.actions_per_minute, summary.duration)}",
        f"  events per minute  {summary.mean_events_per_minute:.1f} mean (monitor firings); "
        f"by minute: {_series(summary.events_per_minute, summary.duration)}",
        f"  peak concurrency   {summary.peak_concurrency} actions{peak_at}",
    ]
    if summary.frozen_actions:
        lines.append(f"  paused             {paused(summary)}")
    return lines


def paused(summary: Summary) -> str:
    """``3 times, 4.200 s in total (5 actions frozen)``: the pauses of a run, in words."""
    times = "once" if summary.pauses == 1 else f"{summary.pauses} times"
    frozen = summary.frozen_actions
    return (
        f"{times}, {summary.paused_time:.3f} s in total "
        f"({frozen} action{'' if frozen == 1 else 's'} frozen)"
    )


def _actions(summary: Summary) -> list[str]:
    if not summary.per_action:
        return []
    header = [
        "action",
        "count",
        "ok",
        "failed",
        "cancelled",
        "skipped",
        "min s",
        "median s",
        "max s",
    ]
    rows = [
        [
            shown(s.name),
            str(s.count),
            str(s.outcomes.succeeded),
            str(s.outcomes.failed),
            str(s.outcomes.cancelled),
            str(s.outcomes.skipped),
            _seconds(s.min_duration),
            _seconds(s.median_duration),
            _seconds(s.max_duration),
        ]
        for s in summary.per_action
    ]
    return ["", *table(header, rows), DURATIONS]


def _resources(summary: Summary) -> list[str]:
    if not summary.resources:
        return []
    header = ["resource", "held s", "use", "acquired", "waits", "max wait s", "preempted"]
    rows = [
        [
            shown(r.name),
            f"{r.held:.3f}",
            f"{100 * r.utilisation:.1f}%",
            str(r.acquisitions),
            str(r.waits),
            f"{r.max_wait:.3f}",
            str(r.preemptions),
        ]
        for r in summary.resources
    ]
    return ["", *table(header, rows)]


def _listing(title: str, lines: Sequence[str]) -> list[str]:
    if not lines:
        return []
    more = [f"    ... and {len(lines) - _SHOWN} more"] if len(lines) > _SHOWN else []
    return ["", f"  {title} ({len(lines)})", *(f"    {line}" for line in lines[:_SHOWN]), *more]


def format_summary(summary: Summary) -> str:
    """The summary as a readable plain-text report (what ``pyrobots-aio replay`` prints).

    Examples:
        >>> from pyrobots_aio.recording import MemoryRecorder, format_summary, summarize
        >>> print(format_summary(summarize(MemoryRecorder().recording())))
        unknown robot: 0.000 s recorded, 0 events, NOT closed (incomplete)
          actions            0: 0 succeeded, 0 failed, 0 cancelled, 0 skipped, 0 not done
          actions per minute 0.0 mean; by minute: 0
          events per minute  0.0 mean (monitor firings); by minute: 0
          peak concurrency   0 actions
    """
    cancels = [f"{c.time:9.3f} s  {shown(c.describe())}" for c in summary.cancellations]
    failures = [
        f"{f.time:9.3f} s  {shown(f.name)}#{f.action}: {shown(f.error)}" for f in summary.failures
    ]
    firings = [f"{shown(name)}: {count}" for name, count in summary.monitor_firings.items()]
    extra = []
    if summary.escalations or summary.abandoned:
        extra = [
            "",
            f"  cancellations escalated: {summary.escalations}; "
            f"actions abandoned: {summary.abandoned}",
        ]
    return "\n".join(
        _overview(summary)
        + _actions(summary)
        + _resources(summary)
        + _listing("cancellations", cancels)
        + _listing("failures", failures)
        + _listing("monitor firings", firings)
        + extra
    )
