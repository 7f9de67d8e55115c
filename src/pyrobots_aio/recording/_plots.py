"""Sensor plots on the timeline's time axis: ``v``, ``w``, the IR ranges, bumper, cliffs...

The rows, those recorded: ``v``, ``w``, each IR range, the bumper, each cliff
sensor, the battery and the wheel encoders.

A plot row draws one recorded series, held from each sample to the next.
Numbers are reduced to the first, lowest, highest and last value of each
pixel column, so that a 10-minute run at 50 Hz draws a few thousand points
and no spike is lost; booleans are filled steps (true: up). The y axis runs
between round numbers (1, 2 or 5 times a power of ten).

For the page's cursor readout, each row's label carries its key and unit, a
number's polyline its drawn values (``data-values``, one per point it steps
to) and a boolean's pulses their times (``data-t0``, ``data-t1``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ._svg import LABEL_W, PLOT_W, Scale, esc, nice_range, tick_text

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from ._recording import Recording, Series

PLOT_H = 40
ROW = PLOT_H + 10
FLAG_H = 14
"""Height of a flag's (a boolean's) pulses: they need no scale."""
FLAG_ROW = FLAG_H + 8
MIN_PULSE = 3.0
"""Narrowest pulse drawn, in pixels."""
UNITS = {"v": "m/s", "w": "rad/s", "encoder_left": "rad", "encoder_right": "rad"}
SPLIT = 4
"""Most steps of a plot's y axis."""


def plotted(recording: Recording) -> list[Series]:
    """The series to plot, in order (those recorded).

    v, w, the IR ranges, the bumper, the cliff sensors, the battery, the wheel encoders.
    """
    samples = recording.samples
    keys = [
        "v",
        "w",
        *sorted(k for k in samples if k.startswith("ir_")),
        "bumper",
        *sorted(k for k in samples if k.startswith("cliff_")),
        "battery",
        "encoder_left",
        "encoder_right",
    ]
    return [samples[k] for k in keys if k in samples and len(samples[k])]


def is_flag(series: Series) -> bool:
    """Whether ``series`` holds only booleans (drawn as pulses)."""
    return all(isinstance(v, bool) for v in series.values)


def row_height(series: Series) -> float:
    """The pixels of the row that draws ``series``."""
    return FLAG_ROW if is_flag(series) else ROW


def unit(key: str) -> str:
    """The unit of the plotted ``key`` ("" when it has none)."""
    return UNITS.get(key, "m" if key.startswith("ir_") else "")


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
    return list(dict.fromkeys([column[0], *middle, column[-1]]))  # a slope's ends are 2, not 4


def draw_plot(series: Series, scale: Scale, top: float, stop: float) -> tuple[list[str], list[str]]:
    """One plot row from ``top``: its label and axis, and what is drawn on the time axis."""
    key, flag = series.key, is_flag(series)
    label = f"{key} ({unit(key)})" if unit(key) else key
    fixed = [
        f'<text class="label" x="22" y="{top + (FLAG_H - 2 if flag else 14):.1f}" '
        f'data-key="{esc(key)}" data-unit="{esc(unit(key))}" '
        f'data-kind="{"flag" if flag else "number"}">{esc(label)}</text>'
    ]
    if flag:
        return [*fixed, _baseline(top + FLAG_H)], _draw_bool(series, scale, top, stop)
    points = _numbers(series)
    if not points:
        return fixed, []
    low, high = min(v for _, v in points), max(v for _, v in points)
    bottom, ceiling, step = nice_range(low, high, SPLIT)
    half_span = ceiling / 2 - bottom / 2 or 1.0  # halves: from -1e308 to 1e308 is no number

    def y(value: float) -> float:
        return top + PLOT_H - (value / 2 - bottom / 2) / half_span * PLOT_H

    steps, values = _steps(_columns(points, scale), scale, y)
    steps.append(f"{scale.x(stop):.1f},{steps[-1].split(',')[1]}")  # the last value, held
    line = (
        f'<polyline class="plot" points="{" ".join(steps)}" data-key="{esc(key)}" '
        f'data-values="{" ".join(values)}"><title>{esc(label)}: {low:.3g} to {high:.3g}</title>'
        "</polyline>"
    )
    return [*fixed, _axis(top, (bottom, ceiling, step))], [line]


def _steps(
    points: Iterable[tuple[float, float]], scale: Scale, y: Callable[[float], float]
) -> tuple[list[str], list[str]]:
    """The polyline's "x,y" points, stepping to each value, and each value as the readout shows it.

    A value that reads and draws as the one held is no step.
    """
    steps: list[str] = []
    values: list[str] = []
    level = ""
    for time, value in points:
        x, text, was = f"{scale.x(time):.1f}", f"{value:.4g}", level
        level = f"{y(value):.1f}"
        if steps and (level, text) == (was, values[-1]):
            continue
        if steps:
            steps.append(f"{x},{was}")  # held until now
        steps.append(f"{x},{level}")
        values.append(text)
    return steps, values


def _axis(top: float, axis: tuple[float, float, float]) -> str:
    """The row's lowest and highest round values, and its baseline."""
    bottom, ceiling, step = axis
    return (
        f'<text class="tick" x="{LABEL_W - 6}" y="{top + 8:.1f}" text-anchor="end">'
        f"{tick_text(ceiling, step)}</text>"
        f'<text class="tick" x="{LABEL_W - 6}" y="{top + PLOT_H:.1f}" text-anchor="end">'
        f"{tick_text(bottom, step)}</text>" + _baseline(top + PLOT_H)
    )


def _baseline(y: float) -> str:
    return (
        f'<line class="baseline" x1="{LABEL_W}" y1="{y:.1f}" x2="{LABEL_W + PLOT_W}" y2="{y:.1f}"/>'
    )


def _draw_bool(series: Series, scale: Scale, top: float, stop: float) -> list[str]:
    """True as a bar up to the top, at least `MIN_PULSE` pixels wide so one tick shows."""
    parts = []
    began: float | None = None
    key = esc(series.key)
    for time, value in [*zip(series.times, series.values, strict=True), (stop, False)]:
        if value and began is None:
            began = time
        elif not value and began is not None:
            x, width = scale.x(began), max(MIN_PULSE, scale.width(began, time))
            t0, t1 = began - scale.start, time - scale.start
            parts.append(
                f'<rect class="plot bool" x="{x:.1f}" y="{top:.1f}" width="{width:.1f}" '
                f'height="{FLAG_H}" data-key="{key}" data-t0="{t0:.3f}" data-t1="{t1:.3f}">'
                f"<title>{key} true from {t0:.3f} to {t1:.3f} s</title></rect>"
            )
            began = None
    return parts
