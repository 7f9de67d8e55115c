"""Sensor plots on the timeline's time axis: ``v``, ``w``, each IR range, the bumper.

A plot row draws one recorded series, held from each sample to the next.
Numbers are reduced to the first, lowest, highest and last value of each
pixel column, so that a 10-minute run at 50 Hz draws a few thousand points
and no spike is lost; booleans are filled steps (true: up).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ._svg import LABEL_W, PLOT_W, Scale, esc

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from ._recording import Recording, Series

PLOT_H = 40
ROW = PLOT_H + 10
MIN_PULSE = 3.0
"""Narrowest pulse drawn, in pixels."""
UNITS = {"v": "m/s", "w": "rad/s"}


def plotted(recording: Recording) -> list[Series]:
    """The series to plot, in order: v, w, the IR ranges, the bumper (those recorded)."""
    samples = recording.samples
    keys = ["v", "w", *sorted(k for k in samples if k.startswith("ir_")), "bumper"]
    return [samples[k] for k in keys if k in samples and len(samples[k])]


def _numbers(series: Series) -> list[tuple[float, float]]:
    return [
        (t, float(v))
        for t, v in zip(series.times, series.values, strict=True)
        if isinstance(v, int | float) and math.isfinite(v)
    ]


def _columns(points: Sequence[tuple[float, float]], scale: Scale) -> Iterable[tuple[float, float]]:
    """Per pixel column: the first, lowest, highest and last point (in time order)."""
    column: list[tuple[float, float]] = []
    at = None
    for time, value in points:
        x = math.floor(scale.x(time))
        if x != at and column:
            yield from _reduced(column)
            column = []
        at = x
        column.append((time, value))
    yield from _reduced(column)


def _reduced(column: list[tuple[float, float]]) -> list[tuple[float, float]]:
    if len(column) <= 4:
        return column
    low, high = min(column, key=lambda p: p[1]), max(column, key=lambda p: p[1])
    middle = sorted({low, high}, key=lambda p: p[0])
    return [column[0], *middle, column[-1]]


def draw_plot(series: Series, scale: Scale, top: float, stop: float) -> list[str]:
    """One plot row from ``top`` (its label, axis and line)."""
    key = series.key
    unit = UNITS.get(key, "m" if key.startswith("ir_") else "")
    label = f"{key} ({unit})" if unit else key
    parts = [f'<text class="label" x="22" y="{top + 14:.1f}">{esc(label)}</text>']
    if all(isinstance(v, bool) for v in series.values):
        return parts + _draw_bool(series, scale, top, stop)
    points = _numbers(series)
    if not points:
        return parts
    low, high = min(v for _, v in points), max(v for _, v in points)
    half_span = high / 2 - low / 2 or 1.0  # halves: from -1e308 to 1e308 is no number

    def y(value: float) -> float:
        return top + PLOT_H - (value / 2 - low / 2) / half_span * PLOT_H

    parts.append(_axis(top, low, high))
    steps: list[str] = []
    level = ""
    for time, value in _columns(points, scale):
        x = f"{scale.x(time):.1f}"
        if steps:
            steps.append(f"{x},{level}")  # held until now
        level = f"{y(value):.1f}"
        steps.append(f"{x},{level}")
    steps.append(f"{scale.x(stop):.1f},{level}")
    parts.append(
        f'<polyline class="plot" points="{" ".join(steps)}" data-key="{esc(key)}">'
        f"<title>{esc(label)}: {low:.3g} to {high:.3g}</title></polyline>"
    )
    return parts


def _axis(top: float, low: float, high: float) -> str:
    return (
        f'<text class="tick" x="{LABEL_W - 6}" y="{top + 8:.1f}" text-anchor="end">'
        f"{high:.3g}</text>"
        f'<text class="tick" x="{LABEL_W - 6}" y="{top + PLOT_H:.1f}" text-anchor="end">'
        f"{low:.3g}</text>"
        f'<line class="baseline" x1="{LABEL_W}" y1="{top + PLOT_H:.1f}" x2="{LABEL_W + PLOT_W}" '
        f'y2="{top + PLOT_H:.1f}"/>'
    )


def _draw_bool(series: Series, scale: Scale, top: float, stop: float) -> list[str]:
    """True as a bar up to the top, at least `MIN_PULSE` pixels wide so one tick shows."""
    parts = [_axis(top, 0, 1)]
    began: float | None = None
    key = esc(series.key)
    for time, value in [*zip(series.times, series.values, strict=True), (stop, False)]:
        if value and began is None:
            began = time
        elif not value and began is not None:
            x, width = scale.x(began), max(MIN_PULSE, scale.width(began, time))
            parts.append(
                f'<rect class="plot bool" x="{x:.1f}" y="{top:.1f}" width="{width:.1f}" '
                f'height="{PLOT_H}" data-key="{key}"><title>{key} true from '
                f"{began - scale.start:.3f} to {time - scale.start:.3f} s</title></rect>"
            )
            began = None
    return parts
