"""Small SVG helpers for the timeline page: scales, axes, escaping, colours."""

from __future__ import annotations

import html
import math
from dataclasses import dataclass

WIDTH = 1200
LABEL_W = 240
RIGHT_PAD = 24
PLOT_W = WIDTH - LABEL_W - RIGHT_PAD
ROW_H = 18
BAR_H = 13
AXIS_H = 28
CHAR_W = 6.2
"""Approximate width of one character of the 11 px labels."""

OUTCOME_COLOURS = {
    "succeeded": "#43a047",
    "failed": "#e53935",
    "cancelled": "#fb8c00",
    "skipped": "#9e9e9e",
    "not_done": "#1e88e5",
}


def esc(text: object) -> str:
    """Escape text for HTML and SVG, attributes included."""
    return html.escape(str(text), quote=True)


def hue(index: int) -> str:
    """The ``index``-th of a sequence of well-separated muted colours (golden-angle hues).

    Muted, so that resource holds are not mistaken for the outcome colours of actions.
    """
    return f"hsl({(210 + index * 137.508) % 360:.0f},28%,52%)"


def nice_step(span: float, most: int) -> float:
    """The smallest of 1, 2, 5 x 10^k that cuts ``span`` into at most ``most`` steps."""
    if span <= 0:
        return 1.0
    raw = span / most
    base = 10 ** math.floor(math.log10(raw))
    for factor in (1, 2, 5, 10):
        if factor * base >= raw:
            return float(factor * base)
    return float(10 * base)


@dataclass(frozen=True, slots=True)
class Scale:
    """Maps loop time to x pixels over the plot area."""

    start: float
    duration: float

    def x(self, time: float) -> float:
        """The x coordinate of ``time``."""
        if self.duration <= 0:
            return float(LABEL_W)
        return LABEL_W + (time - self.start) / self.duration * PLOT_W

    def width(self, begin: float, end: float) -> float:
        """The width of a bar from ``begin`` to ``end``, at least one pixel so it shows."""
        return max(1.0, self.x(end) - self.x(begin))


def time_axis(scale: Scale, height: float) -> list[str]:
    """Tick labels (seconds since the start) on top and grid lines down ``height`` pixels."""
    step = nice_step(scale.duration, 12)
    parts = [f'<g class="axis"><text x="{LABEL_W - 8}" y="16" text-anchor="end">seconds</text>']
    ticks = int(scale.duration // step) + 1 if scale.duration > 0 else 1
    for i in range(ticks):
        x = scale.x(scale.start + i * step)
        label = f"{i * step:g}"
        parts.append(f'<text x="{x:.1f}" y="16" text-anchor="middle">{label}</text>')
        parts.append(
            f'<line class="grid" x1="{x:.1f}" y1="{AXIS_H - 6}" x2="{x:.1f}" y2="{height:.1f}"/>'
        )
    parts.append("</g>")
    return parts


def rect(cls: str, box: tuple[float, float, float, float], title: str, fill: str = "") -> str:
    """A bar (``box``: x, y, width, height) with a tooltip, filled by its class or ``fill``."""
    x, y, w, h = box
    style = f' style="fill:{fill}"' if fill else ""
    return (
        f'<rect class="{cls}" x="{x:.1f}" y="{y:.1f}" width="{w:.1f}" height="{h:.1f}"{style}>'
        f"<title>{esc(title)}</title></rect>"
    )


def label(text: str, y: float, depth: int = 0, cls: str = "label") -> str:
    """A row label in the left column, indented by ``depth``."""
    return f'<text class="{cls}" x="{8 + 14 * depth}" y="{y + BAR_H - 2:.1f}">{esc(text)}</text>'


def bar_chart_axis(top: float, height: float, peak: float) -> tuple[list[str], float]:
    """The y axis of a chart ``height`` high whose values reach ``peak``; returns its maximum."""
    step = nice_step(peak, 5) if peak > 0 else 1.0
    ceiling = step * max(1, math.ceil(peak / step))
    parts = ['<g class="axis">']
    ticks = round(ceiling / step)
    for i in range(ticks + 1):
        y = top + height - i * step / ceiling * height
        parts.append(
            f'<line class="grid" x1="{LABEL_W}" y1="{y:.1f}" x2="{LABEL_W + PLOT_W}" y2="{y:.1f}"/>'
        )
        parts.append(
            f'<text x="{LABEL_W - 8}" y="{y + 4:.1f}" text-anchor="end">{i * step:g}</text>'
        )
    parts.append("</g>")
    return parts, ceiling
