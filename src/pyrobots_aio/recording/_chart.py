"""The actions/events chart of the replay page: counts per bucket, on the timeline's axis.

Each bar counts what happened in its bucket (no scaling: a bucket of 10 s
shows the actions started in those 10 s), and the buckets sit on the same time
axis as the timeline above, with the same ticks.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from . import _svg
from ._summary import per_bucket
from ._svg import LABEL_W, WIDTH, cursor_marks, timed_attributes

if TYPE_CHECKING:
    from ._analysis import Analysis
    from ._recording import Recording
    from ._svg import Scale

BUCKETS = (1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600)
"""Bucket widths in seconds; the chart takes the narrowest giving at most `MAX_BARS` buckets."""
MAX_BARS = 60
HEIGHT = 160
TOP = 12


def bucket_width(duration: float) -> float:
    """The narrowest bucket (seconds) cutting ``duration`` into at most `MAX_BARS` buckets."""
    for width in BUCKETS:
        if duration / width <= MAX_BARS:
            return float(width)
    return float(BUCKETS[-1] * math.ceil(duration / (BUCKETS[-1] * MAX_BARS)))


def _per(width: float) -> str:
    return "per minute" if width == 60 else f"per {width:g} s"


def rate_chart(recording: Recording, found: Analysis, scale: Scale) -> str:
    """The SVG chart: actions spawned and monitor firings per bucket, on ``scale``."""
    width = bucket_width(recording.duration)
    start, duration = recording.start, recording.duration
    actions = per_bucket((s.spawned for s in found.spans.values()), start, duration, width)
    events = per_bucket((e.time for e in found.firings), start, duration, width)
    parts, ceiling = _svg.bar_chart_axis(TOP, HEIGHT, max(*actions, *events))
    bars: list[str] = []
    for i, (a, e) in enumerate(zip(actions, events, strict=True)):
        left, right = scale.x(start + i * width), scale.x(start + min(duration, (i + 1) * width))
        bar = max(1.0, (right - left) / 2 - 1)
        span = f"{i * width:g}-{(i + 1) * width:g} s"
        for offset, cls, count, what in (
            (0.0, "rate-actions", a, "actions started"),
            (bar, "rate-events", e, "events"),
        ):
            h = count / ceiling * HEIGHT
            title = f"{span}: {count} {what}"
            bars.append(_svg.rect(cls, (left + offset, TOP + HEIGHT - h, bar, h), title))
    bottom = TOP + HEIGHT
    parts.append(_svg.zoomable(bottom, bars))
    parts += _svg.time_axis(scale, bottom, label_y=bottom + 16, top=TOP)
    legend_y = bottom + 34
    parts.append(
        f'<text x="{LABEL_W}" y="{legend_y}">counts {_per(width)} (blue: actions started; '
        "purple: events, i.e. monitor firings)</text>"
    )
    parts.append(cursor_marks(TOP, bottom, TOP + 10))
    total = legend_y + 10
    return (
        f'<svg class="rates" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {WIDTH} {total}" '
        f'width="{WIDTH}" height="{total}" {timed_attributes(scale)}>' + "".join(parts) + "</svg>"
    )
