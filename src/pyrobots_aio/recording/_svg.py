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


def css_class(text: object, default: str = "other") -> str:
    """``text`` as a CSS class name if it is a plain word (letters, digits, ``_``, ``-``)."""
    word = str(text)
    return word if word and word.replace("_", "").replace("-", "").isalnum() else default


_RAMP = ((68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37))
"""Viridis at 0, 1/4, 1/2, 3/4 and 1: dark purple (start) to yellow (end), for the path."""


def ramp(fraction: float) -> str:
    """The colour of ``fraction`` (0 to 1) of the way along the run."""
    f = min(1.0, max(0.0, fraction if math.isfinite(fraction) else 0.0)) * (len(_RAMP) - 1)
    i = min(int(f), len(_RAMP) - 2)
    a, b, w = _RAMP[i], _RAMP[i + 1], f - i
    r, g, bl = (round(x + (y - x) * w) for x, y in zip(a, b, strict=True))
    return f"#{r:02x}{g:02x}{bl:02x}"


HOLD_COLOURS = (
    "#3949ab",  # indigo
    "#00838f",  # dark cyan
    "#6d4c41",  # brown
    "#8e24aa",  # purple
    "#546e7a",  # blue grey
    "#827717",  # olive
    "#283593",  # navy
)
"""Colours of resource holds by holder: none near the outcome colours (green, red, orange)."""


def hue(index: int) -> str:
    """The colour of the ``index``-th holder of resources (see `HOLD_COLOURS`; then repeats)."""
    return HOLD_COLOURS[index % len(HOLD_COLOURS)]


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


def tick_text(value: float, step: float) -> str:
    """``value``, a multiple of ``step``, with the decimals ``step`` needs and no float noise.

    ``0.30000000000000004`` on a step of 0.1 reads ``0.3``, zero reads ``0``; a
    value too large or small for plain decimals reads in three significant
    digits (``1e+18``).
    """
    decimals = max(0, -math.floor(math.log10(step))) if 0 < step < math.inf else 0
    if decimals > 6 or abs(value) >= 1e9:
        return f"{value:.3g}"
    text = f"{value:.{decimals}f}"
    return "0" if float(text) == 0 else text  # not "-0.0", nor "0.0000"


def nice_range(low: float, high: float, most: int) -> tuple[float, float, float]:
    """``low`` and ``high`` widened to multiples of a 1/2/5 step, at most ``most`` steps apart.

    Returns (bottom, top, step). A constant gets a step of its own size; a
    range too wide for floats (-1e308 to 1e308) keeps its own ends.
    """
    span = high - low or abs(high) or 1.0
    if math.isfinite(span):
        step = nice_step(span, most)
        bottom, top = math.floor(low / step) * step, math.ceil(high / step) * step
        if math.isfinite(top):
            return bottom, max(top, bottom + step), step
    return low, high, high / 2 - low / 2 or 1.0


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


def ticks(scale: Scale) -> list[tuple[float, str]]:
    """The x of each time tick and its label (seconds since the start), at most 13."""
    step = nice_step(scale.duration, 12)
    count = int(scale.duration // step) + 1 if 0 < scale.duration < math.inf else 1
    return [(scale.x(scale.start + i * step), tick_text(i * step, step)) for i in range(count)]


def time_axis(
    scale: Scale, height: float, label_y: float = 16, top: float = AXIS_H - 6
) -> list[str]:
    """Tick labels (seconds since the start) at ``label_y`` and grid lines down to ``height``.

    The page's zoom draws them again for the time it shows, from the group's ``data-`` attributes.
    """
    parts = [
        f'<g class="axis time" data-label-y="{label_y:.0f}" data-top="{top:.1f}" '
        f'data-bottom="{height:.1f}"><text x="{LABEL_W - 8}" y="{label_y:.0f}" '
        'text-anchor="end">seconds since start</text>'
    ]
    for x, label in ticks(scale):
        parts.append(f'<text x="{x:.1f}" y="{label_y:.0f}" text-anchor="middle">{label}</text>')
        parts.append(
            f'<line class="grid" x1="{x:.1f}" y1="{top:.1f}" x2="{x:.1f}" y2="{height:.1f}"/>'
        )
    parts.append("</g>")
    return parts


def rect(cls: str, box: tuple[float, float, float, float], title: str, fill: str = "") -> str:
    """A bar (``box``: x, y, width, height) with a tooltip, filled by its class or ``fill``."""
    x, y, w, h = box
    style = f' style="fill:{esc(fill)}"' if fill else ""
    return (
        f'<rect class="{esc(cls)}" x="{x:.1f}" y="{y:.1f}" width="{w:.1f}" height="{h:.1f}"'
        f"{style}><title>{esc(title)}</title></rect>"
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


def cursor_marks(top: float, bottom: float, label_y: float) -> str:
    """The hover cursor of a figure on the time axis (hidden until the script moves it)."""
    return (
        f'<line class="cursor" x1="0" y1="{top:.1f}" x2="0" y2="{bottom:.1f}" '
        f'style="display:none"/><text class="cursor-time" x="-99" y="{label_y:.1f}"></text>'
    )


def zoomable(height: float, parts: list[str]) -> str:
    """``parts`` in a viewport over the plot area: the page's zoom moves them, it clips them."""
    return (
        f'<svg class="zoom" x="{LABEL_W}" y="0" width="{PLOT_W}" height="{height:.0f}" '
        f'viewBox="{LABEL_W} 0 {PLOT_W} {height:.0f}">' + "".join(parts) + "</svg>"
    )


def timed_attributes(scale: Scale) -> str:
    """What the page's script needs to turn an x of this figure into a time, and back."""
    return f'data-x0="{LABEL_W}" data-w="{PLOT_W}" data-duration="{scale.duration:.6f}"'
