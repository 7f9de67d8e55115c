"""The actions/events-per-minute chart of the timeline page (an SVG bar chart)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from . import _svg
from ._summary import MINUTE, per_bucket
from ._svg import LABEL_W, PLOT_W, WIDTH

if TYPE_CHECKING:
    from ._analysis import Analysis
    from ._recording import Recording

BUCKETS = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600)
"""Bucket widths in seconds; the chart takes the narrowest giving at most `MAX_BARS` buckets."""
MAX_BARS = 60
HEIGHT = 180
TOP = 12


def bucket_width(duration: float) -> float:
    """The narrowest bucket (seconds) cutting ``duration`` into at most `MAX_BARS` buckets."""
    for width in BUCKETS:
        if duration / width <= MAX_BARS:
            return float(width)
    return float(BUCKETS[-1] * math.ceil(duration / (BUCKETS[-1] * MAX_BARS)))


def _x_labels(count: int, width: float) -> list[str]:
    every = max(1, math.ceil(count / 12))
    slot = PLOT_W / count
    y = TOP + HEIGHT + 16
    return [
        f'<text x="{LABEL_W + i * slot:.1f}" y="{y}" text-anchor="middle">{i * width:g}</text>'
        for i in range(0, count + 1, every)
    ]


def rate_chart(recording: Recording, found: Analysis) -> str:
    """The SVG chart: actions spawned and monitor firings per minute, bucket by bucket."""
    width = bucket_width(recording.duration)
    start, duration = recording.start, recording.duration
    actions = per_bucket((s.spawned for s in found.spans.values()), start, duration, width)
    events = per_bucket((e.time for e in found.firings), start, duration, width)
    scale = MINUTE / width
    peak = max(*actions, *events) * scale
    parts, ceiling = _svg.bar_chart_axis(TOP, HEIGHT, peak)
    slot = PLOT_W / len(actions)
    bar = max(1.0, slot / 2 - 1)
    for i, (a, e) in enumerate(zip(actions, events, strict=True)):
        x = LABEL_W + i * slot
        span = f"{i * width:g}-{(i + 1) * width:g} s"
        for offset, cls, count, what in (
            (0.0, "rate-actions", a, "actions"),
            (bar, "rate-events", e, "events"),
        ):
            h = count * scale / ceiling * HEIGHT
            title = f"{span}: {count} {what} ({count * scale:g} per minute)"
            parts.append(_svg.rect(cls, (x + offset, TOP + HEIGHT - h, bar, h), title))
    parts += _x_labels(len(actions), width)
    legend_y = TOP + HEIGHT + 34
    parts.append(
        f'<text x="{LABEL_W}" y="{legend_y}">per minute, in buckets of {width:g} s '
        f"(blue: actions started; purple: events, i.e. monitor firings)</text>"
    )
    total = legend_y + 10
    return (
        f'<svg class="rates" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH} {total}" '
        f'width="{WIDTH}" height="{total}">' + "".join(parts) + "</svg>"
    )
