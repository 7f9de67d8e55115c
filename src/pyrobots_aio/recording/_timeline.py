"""`render_timeline_html`: the replay page, one self-contained HTML file.

Top to bottom:

- the **map** (`_map`): the arena from the recorded floor plan, the path
  coloured by time, bumps, cliffs, preemptions and (un)docking where they
  happened;
- the **timeline** (figure 1 of the pyRobots paper): one row per action
  *path* (an action name under its parent's row, so children sit indented
  under their parents), each instance a bar from its start to its end
  coloured by outcome, with a tooltip giving the parent, the outcome and, for
  a cancelled action, who cancelled it and why; each spell an action spent
  paused (frozen) is hatched over its bar, with who paused it and why in its
  own tooltip; instances of one path that overlap take extra lanes. Below:
  each resource's holds (coloured by holder, named in the legend), waits and
  preemptions; monitor firings; boolean state; then **plots** of ``v``,
  ``w``, each IR range, the bumper, and the cliffs, battery and encoders
  when recorded (`_plots`);
- actions started and events (monitor firings) per bucket of time (figure 2),
  on the same time axis;
- a readout of each plotted value at the cursor, fixed at the window's bottom.

Hovering the path shows the moment on the timeline and plots (a cursor), and
hovering the timeline shows where the robot was and faced on the map; the
wheel zooms and a drag pans the time axis of every figure: a small static
script does it (`_script`), reading only ``data-`` attributes. What each
figure draws on the time axis sits in a nested ``svg.zoom`` over its plot
area (which clips it); labels and y axes stay outside. Inline CSS, SVG and
that script; no external asset. Every value taken from the recording is
escaped, attributes included, and only plain words become class names.
"""

from __future__ import annotations

import heapq
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from . import _svg
from ._analysis import NOT_DONE, Analysis, Interval, Pause, Span, analyse, by_resource
from ._chart import rate_chart
from ._format import paused
from ._map import colour_bar, marks, render_map
from ._plots import draw_plot, plotted, row_height
from ._script import MAX_ZOOM
from ._script import SCRIPT as _SCRIPT
from ._summary import summarize
from ._svg import AXIS_H, BAR_H, ROW_H, WIDTH, Scale, cursor_marks, esc, timed_attributes

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from pyrobots_aio import MonitorFired

    from ._recording import Recording

T = TypeVar("T")

_CSS = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 24px; color: #212121; }
h1 { font-size: 20px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 24px 0 6px; }
.facts { color: #555; margin: 0 0 8px; } .error { color: #b71c1c; font-weight: 600; }
svg { max-width: 100%; height: auto; display: block; }
svg.timeline, svg.rates { width: 100%; max-width: 1200px; }
svg text { font: 11px sans-serif; fill: #333; } .section { font-weight: 700; }
.grid { stroke: #e0e0e0; stroke-width: 1; } rect { stroke: #fff; stroke-width: 0.5; }
rect:hover { stroke: #000; stroke-width: 1; } text.in { fill: #fff; pointer-events: none; }
text.in.dark { fill: #37474f; } text.out { fill: #455a64; pointer-events: none; }
.succeeded { fill: #43a047; } .failed { fill: #e53935; } .cancelled { fill: #fb8c00; }
.skipped { fill: #9e9e9e; } .not_done { fill: #1e88e5; }
rect.paused { fill: url(#paused-hatch); } pattern rect { stroke: none; }
.wait { fill: #cfd8dc; } .state-on { fill: #5e35b1; } .cancel-mark { stroke: #000; }
.preempt { fill: #000; } .firing { stroke: #6a1b9a; stroke-width: 2; }
.rate-actions { fill: #1e88e5; } .rate-events { fill: #8e24aa; }
.plot { fill: none; stroke: #1565c0; stroke-width: 1; }
rect.plot.bool { fill: #d50000; stroke: none; }
.baseline { stroke: #bdbdbd; } text.tick { fill: #757575; font-size: 10px; }
.cursor { stroke: #d50000; stroke-width: 1; pointer-events: none; }
svg.map { background: #f5f3ee; border: 1px solid #ddd; }
.shape { stroke: #424242; stroke-width: 1; fill: #90a4ae; }
.trail { fill: none; stroke-width: 2.5; stroke-linejoin: round; stroke-linecap: round; }
.mark { stroke-width: 2; fill: none; } .mark.bump { stroke: #d50000; stroke-width: 3; }
.mark.cliff { fill: #ff6f00; stroke: #000; stroke-width: 1; }
.mark.preempt { fill: #000; stroke: #fff; stroke-width: 1; }
.mark.dock { fill: #2e7d32; stroke: #fff; stroke-width: 1; }
.mark.undock { fill: #fff; stroke: #2e7d32; }
.mark.disturbance { fill: none; stroke: #6a1b9a; stroke-width: 2; }
.start { fill: #fff; stroke: #000; } .here { fill: none; stroke: #d50000; stroke-width: 3; }
.scalebar line { stroke: #000; stroke-width: 2; }
.legend span { display: inline-block; margin-right: 14px; }
.legend i { display: inline-block; width: 12px; height: 12px; margin-right: 4px;
  vertical-align: -1px; box-shadow: inset 0 0 0 1px rgba(0, 0, 0, 0.3); }
.ramp i { width: 8px; margin: 0; box-shadow: none; }
svg.zoom polyline { vector-effect: non-scaling-stroke; } text.later { display: none; }
svg.timeline, svg.rates { cursor: crosshair; } svg.dragging { cursor: grabbing; }
.heading { fill: none; stroke: #37474f; stroke-width: 1.5; opacity: 0.7; }
.here-heading { fill: none; stroke: #d50000; stroke-width: 3; stroke-linecap: round; }
text.count { font: bold 11px sans-serif; fill: #000; stroke: #fff; stroke-width: 3px;
  paint-order: stroke; pointer-events: none; }
.zoombar { margin: 4px 0; color: #555; } .zoombar .hint { font-size: 12px; }
.readout { position: fixed; left: 0; right: 0; bottom: 0; padding: 4px 24px;
  background: rgba(255, 255, 255, 0.95); border-top: 1px solid #bbb; font: 12px/1.5 monospace; }
.readout span { display: inline-block; margin-right: 16px; white-space: nowrap; }
body { padding-bottom: 64px; }
"""

_OUTCOMES = frozenset(_svg.OUTCOME_COLOURS)
PAUSED_PALE, PAUSED_INK = "#eceff1", "#a7b5bc"
"""The paused hatch: ink stripes on a pale ground, unlike any outcome's plain colour."""
_HATCH = (
    '<defs><pattern id="paused-hatch" width="6" height="6" patternUnits="userSpaceOnUse" '
    f'patternTransform="rotate(45)"><rect width="6" height="6" style="fill:{PAUSED_PALE}"/>'
    f'<rect width="2" height="6" style="fill:{PAUSED_INK}"/></pattern></defs>'
)
_PAUSED_SWATCH = f"repeating-linear-gradient(45deg, {PAUSED_INK} 0 2px, {PAUSED_PALE} 2px 5px)"


@dataclass(slots=True)
class _Node:
    """A row of the action timeline: one name under one parent row."""

    name: str
    depth: int
    spans: list[Span] = field(default_factory=list)
    children: dict[str, _Node] = field(default_factory=dict)


def _tree(found: Analysis) -> _Node:
    root = _Node("", -1)
    where: dict[int, _Node] = {}
    for span in sorted(found.spans.values(), key=lambda s: (s.spawned, s.id)):
        parent = where.get(span.parent, root) if span.parent is not None else root
        node = parent.children.get(span.name)
        if node is None:
            node = parent.children[span.name] = _Node(span.name, parent.depth + 1)
        node.spans.append(span)
        where[span.id] = node
    return root


def _walk(node: _Node) -> Iterable[_Node]:
    """The rows under ``node``, depth first, children in insertion order (first spawned first).

    A loop, not recursion: a recorded tree can be thousands of actions deep.
    """
    stack = list(reversed(node.children.values()))
    while stack:
        child = stack.pop()
        yield child
        stack.extend(reversed(child.children.values()))


def _lanes(
    items: Sequence[T], begin: Callable[[T], float], end: Callable[[T], float]
) -> list[list[T]]:
    """Pack intervals into lanes so that no two in a lane overlap.

    Each interval, by start, goes to the first lane free at its start (first
    fit); two heaps find that lane in log time however many lanes there are:
    the lanes in use by when they are free, and the free lanes by number.
    """
    lanes: list[list[T]] = []
    busy: list[tuple[float, int]] = []
    free: list[int] = []
    for item in sorted(items, key=begin):
        b = begin(item)
        while busy and busy[0][0] <= b:
            heapq.heappush(free, heapq.heappop(busy)[1])
        if free:
            lane = heapq.heappop(free)
        else:
            lane = len(lanes)
            lanes.append([])
        lanes[lane].append(item)
        heapq.heappush(busy, (end(item), lane))
    return lanes


class _Canvas:
    """The timeline figure being drawn, top to bottom."""

    def __init__(self, recording: Recording, found: Analysis) -> None:
        self.scale = Scale(recording.start, recording.duration)
        self.start, self.stop = recording.start, recording.stop
        self.found = found
        self.parts: list[str] = []
        """Drawn in place: labels, the plots' y axes."""
        self.timed: list[str] = []
        """Drawn on the time axis, where the page's zoom moves them."""
        self.y = float(AXIS_H)
        self._hues: dict[str, str] = {}

    @property
    def holders(self) -> list[str]:
        """The names of the actions that held resources, in order of first hold."""
        return list(self._hues)

    def hue(self, name: str) -> str:
        """The colour of resource holds by actions called ``name`` (one per name)."""
        colour = self._hues.get(name)
        if colour is None:
            colour = self._hues[name] = _svg.hue(len(self._hues))
        return colour

    def end_of(self, span: Span) -> float:
        """When ``span`` finished, or the end of the recording if it had not."""
        return span.finished if span.finished is not None else self.stop

    def end_of_pause(self, spell: Pause) -> float:
        """When ``spell`` ended, or the end of the recording if it had not."""
        return spell.end if spell.end is not None else self.stop

    def rel(self, time: float) -> str:
        return f"{time - self.start:.3f}"

    def section(self, title: str) -> None:
        self.y += 6
        self.parts.append(_svg.label(title, self.y, cls="section"))
        self.y += ROW_H

    def bar(
        self,
        cls: str,
        begin: float,
        end: float,
        title: str,
        *,
        text: str = "",
        fill: str = "",
        room: float = 0.0,
        least: float = 1.0,
        paused: Sequence[tuple[float, float, str]] = (),
    ) -> None:
        """A bar on the current row, with a tooltip and ``text`` inside if it fits.

        Otherwise ``text`` goes right of the bar when the next ``room`` pixels
        are free, else inside, hidden until the page's zoom makes room (and is
        left to the tooltip when even `MAX_ZOOM` would not). ``least`` is
        the narrowest bar drawn, in pixels, so that short pulses show.
        ``paused`` spells (begin, end, tooltip) are hatched over the bar, under
        its text (dark when the bar begins paused).
        """
        x, w = self.scale.x(begin), max(least, self.scale.width(begin, end))
        self.timed.append(_svg.rect(cls, (x, self.y, w, BAR_H), title, fill))
        for start, stop, about in paused:
            box = (self.scale.x(start), self.y, self.scale.width(start, stop), BAR_H)
            self.timed.append(_svg.rect("paused", box, about))
        if not text:
            return
        y = self.y + BAR_H - 3
        needed = len(text) * _svg.CHAR_W + 4
        dark = cls == "wait" or any(start <= begin < stop for start, stop, _ in paused)
        ink, at = "in dark" if dark else "in", f'x="{x + 2:.1f}" y="{y:.1f}"'
        if w >= needed:
            self.timed.append(f'<text class="{ink}" {at}>{esc(text)}</text>')
        elif room - w >= needed + 2 and x + w + needed < WIDTH:
            self.timed.append(
                f'<text class="out" x="{x + w + 3:.1f}" y="{y:.1f}">{esc(text)}</text>'
            )
        elif needed / w <= MAX_ZOOM:  # the page's zoom shows it once the bar is that much wider
            self.timed.append(
                f'<text class="{ink} later" {at} data-fit="{needed / w:.3f}">{esc(text)}</text>'
            )

    def lanes(
        self, items: Sequence[T], begin: Callable[[T], float], end: Callable[[T], float]
    ) -> Iterable[tuple[int, T, float]]:
        """Each item's lane, the item, and the pixels free from its start to the next one."""
        for number, lane in enumerate(_lanes(items, begin, end)):
            for i, item in enumerate(lane):
                after = begin(lane[i + 1]) if i + 1 < len(lane) else None
                limit = self.scale.x(after) if after is not None else WIDTH
                yield number, item, limit - self.scale.x(begin(item))

    def tick(self, cls: str, time: float, title: str) -> None:
        x = self.scale.x(time)
        self.timed.append(
            f'<line class="{cls}" x1="{x:.1f}" y1="{self.y:.1f}" x2="{x:.1f}" '
            f'y2="{self.y + BAR_H:.1f}"><title>{esc(title)}</title></line>'
        )

    def svg(self) -> str:
        height = self.y + 8
        axis = _svg.time_axis(self.scale, height)
        cursor = cursor_marks(AXIS_H - 6, height, AXIS_H + 6)
        return (
            f'<svg class="timeline" xmlns="http://www.w3.org/2000/svg" '
            f'viewBox="0 0 {WIDTH} {height:.0f}" width="{WIDTH}" height="{height:.0f}" '
            f"{timed_attributes(self.scale)}>{_HATCH}"
            + "".join([*axis, *self.parts, _svg.zoomable(height, self.timed), cursor])
            + "</svg>"
        )


def _action_title(canvas: _Canvas, span: Span) -> str:
    end = span.finished if span.finished is not None else canvas.stop
    lines = [
        f"{span.name}#{span.id}: {span.outcome.replace('_', ' ')}",
        f"{canvas.rel(span.begin)} -> {canvas.rel(end)} s ({end - span.begin:.3f} s)",
        f"parent: {canvas.found.label(span.parent) or 'root scope'}",
    ]
    if span.cancelled_at is not None:
        who = canvas.found.label(span.by) or "outside any action"
        lines.append(f"cancel requested at {canvas.rel(span.cancelled_at)} s by {who}")
        if span.reason:
            lines.append(f"reason: {span.reason}")
    if span.error:
        lines.append(f"error: {span.error}")
    if span.pauses:
        frozen = sum(canvas.end_of_pause(p) - p.start for p in span.pauses)
        times = "once" if len(span.pauses) == 1 else f"{len(span.pauses)} times"
        lines.append(f"paused {times}, {frozen:.3f} s in total")
    return "\n".join(lines)


def _pause_title(canvas: _Canvas, span: Span, spell: Pause) -> str:
    end = canvas.end_of_pause(spell)
    lines = [
        f"{span.name}#{span.id}: paused",
        f"{canvas.rel(spell.start)} -> {canvas.rel(end)} s ({end - spell.start:.3f} s), "
        + spell.ended,
    ]
    if spell.root is not None and spell.root != span.id:
        lines.append(f"frozen with {canvas.found.label(spell.root)}")
    if spell.by is not None:
        lines.append(f"paused by {canvas.found.label(spell.by)}")
    if spell.reason:
        lines.append(f"reason: {spell.reason}")
    return "\n".join(lines)


def _paused(canvas: _Canvas, span: Span) -> list[tuple[float, float, str]]:
    """The spells ``span`` spent paused, within its bar, with their tooltips."""
    first, last = span.begin, canvas.end_of(span)
    spells = []
    for spell in span.pauses:
        begin, end = max(first, spell.start), min(last, canvas.end_of_pause(spell))
        if end >= begin:
            spells.append((begin, end, _pause_title(canvas, span, spell)))
    return spells


def _begin(span: Span) -> float:
    return span.begin


def _lane_label(canvas: _Canvas, text: str, lane: int, depth: int) -> None:
    """The label of a row: ``text`` on its first lane, "(lane N)" under it on the others."""
    shown = text if lane == 0 else f"{text} (lane {lane + 1})"
    canvas.parts.append(_svg.label(shown, canvas.y, depth if lane == 0 else depth + 1))


def _draw_actions(canvas: _Canvas) -> None:
    canvas.section("actions")
    for node in _walk(_tree(canvas.found)):
        title = f"{node.name} x{len(node.spans)}"
        current = -1
        for lane, span, room in canvas.lanes(node.spans, _begin, canvas.end_of):
            if lane != current:
                canvas.y += ROW_H if current >= 0 else 0
                current = lane
                _lane_label(canvas, title if lane == 0 else node.name, lane, node.depth)
            outcome = span.outcome if span.outcome in _OUTCOMES else NOT_DONE
            canvas.bar(
                f"action {outcome}",
                span.begin,
                canvas.end_of(span),
                _action_title(canvas, span),
                text=f"{span.name}#{span.id}",
                room=room,
                paused=_paused(canvas, span),
            )
            if span.cancelled_at is not None:
                canvas.tick("cancel-mark", span.cancelled_at, f"cancel requested: {span.reason}")
        canvas.y += ROW_H


def _interval_rows(
    canvas: _Canvas, intervals: list[Interval], cls: str, what: str, name: str
) -> None:
    ends = [i.end if i.end is not None else canvas.stop for i in intervals]
    index = {id(i): e for i, e in zip(intervals, ends, strict=True)}
    current = -1
    for lane, i, room in canvas.lanes(intervals, lambda i: i.start, lambda i: index[id(i)]):
        if lane != current:
            canvas.y += ROW_H if current >= 0 else 0
            current = lane
            _lane_label(canvas, name, lane, 1 if cls == "hold" else 2)
        end = index[id(i)]
        title = (
            f"{i.resource} {what} {i.name}#{i.action} (priority {i.priority})\n"
            f"{canvas.rel(i.start)} -> {canvas.rel(end)} s ({end - i.start:.3f} s)"
            + ("" if i.outcome == "held" else f", {i.outcome.replace('_', ' ')}")
        )
        fill = canvas.hue(i.name) if cls == "hold" else ""
        canvas.bar(cls, i.start, end, title, text=f"{i.name}#{i.action}", fill=fill, room=room)
    if current >= 0:
        canvas.y += ROW_H


def _draw_resources(canvas: _Canvas) -> None:
    uses = by_resource(canvas.found)
    if not uses:
        return
    canvas.section("resources")
    for name, use in uses.items():
        top = canvas.y
        if use.holds:
            _interval_rows(canvas, use.holds, "hold", "held by", name)
        else:
            canvas.parts.append(_svg.label(name, canvas.y, 1))
            canvas.y += ROW_H
        for event in use.preemptions:
            x = canvas.scale.x(event.time)
            canvas.timed.append(
                f'<path class="preempt" transform="translate({x:.1f},{top:.1f})" '
                f'd="M-5,0 h10 l-5,7 z"><title>{esc(event.reason)}</title></path>'
            )
        if use.waits:
            _interval_rows(canvas, use.waits, "wait", "awaited by", "waiting")


def _draw_firings(canvas: _Canvas) -> None:
    by_name: dict[str, list[MonitorFired]] = {}
    for event in canvas.found.firings:
        by_name.setdefault(event.name or "?", []).append(event)
    if not by_name:
        return
    canvas.section("monitor firings")
    for name in sorted(by_name):
        canvas.parts.append(_svg.label(name, canvas.y, 1))
        for event in by_name[name]:
            canvas.tick("firing", event.time, f"{name} fired at {canvas.rel(event.time)} s")
        canvas.y += ROW_H


def _state_spans(recording: Recording) -> dict[str, list[tuple[float, float]]]:
    """For each boolean state key sampled: the intervals during which it was true."""
    spans: dict[str, list[tuple[float, float]]] = {}
    for key, series in recording.samples.items():
        values = series.values
        if not any(v is True for v in values) or not all(isinstance(v, bool) for v in values):
            continue
        found = spans[key] = []
        began: float | None = None
        for time, value in zip(series.times, series.values, strict=True):
            if value and began is None:
                began = time
            elif not value and began is not None:
                found.append((began, time))
                began = None
        if began is not None:
            found.append((began, recording.stop))
    return spans


def _draw_state(canvas: _Canvas, recording: Recording) -> None:
    spans = _state_spans(recording)
    if not spans:
        return
    canvas.section("state (true)")
    for key in sorted(spans):
        canvas.parts.append(_svg.label(key, canvas.y, 1))
        for begin, end in spans[key]:
            title = f"{key} true {canvas.rel(begin)} -> {canvas.rel(end)} s"
            canvas.bar("state-on", begin, end, title, least=3.0)
        canvas.y += ROW_H


def _draw_plots(canvas: _Canvas, recording: Recording) -> None:
    series = plotted(recording)
    if not series:
        return
    canvas.section("sensors")
    for one in series:
        fixed, timed = draw_plot(one, canvas.scale, canvas.y, canvas.stop)
        canvas.parts += fixed
        canvas.timed += timed
        canvas.y += row_height(one)


def _facts(recording: Recording) -> str:
    summary = summarize(recording)
    o = summary.outcomes
    robot = esc(summary.robot or "unknown robot")
    seed = f", seed {summary.seed}" if summary.seed is not None else ""
    where = f"{esc(recording.path)} &middot; " if recording.path else ""
    pauses = f"paused {paused(summary)} &middot; " if summary.frozen_actions else ""
    return (
        f'<p class="facts">{where}{robot}{seed} &middot; {summary.duration:.3f} s &middot; '
        f"{summary.actions} actions ({o.succeeded} succeeded, {o.failed} failed, "
        f"{o.cancelled} cancelled, {o.skipped} skipped, {o.not_done} not done) &middot; "
        f"peak concurrency {summary.peak_concurrency} &middot; {pauses}"
        f"{summary.mean_actions_per_minute:.1f} actions and "
        f"{summary.mean_events_per_minute:.1f} events per minute</p>"
    )


def _swatches(items: Iterable[tuple[str, str]]) -> str:
    return "".join(f'<span><i style="background:{c}"></i>{esc(t)}</span>' for t, c in items)


def _legend(canvas: _Canvas) -> str:
    swatches = [(name.replace("_", " "), colour) for name, colour in _svg.OUTCOME_COLOURS.items()]
    swatches += [
        ("paused", _PAUSED_SWATCH),
        ("waiting for a resource", "#cfd8dc"),
        ("state true", "#5e35b1"),
    ]
    holders = ""
    if canvas.holders:
        holders = (
            '<p class="legend">resource held by: '
            + _swatches((name, canvas.hue(name)) for name in canvas.holders)
            + '<span><i style="background:#000"></i>preempted (triangle)</span></p>'
        )
    return f'<p class="legend">actions: {_swatches(swatches)}</p>{holders}'


_MARKS = (
    ("bump", "bump", "#d50000"),
    ("cliff", "cliff", "#ff6f00"),
    ("preempt", "preemption", "#000"),
    ("dock", "docked", "#2e7d32"),
    ("undock", "undocked", "#fff"),
)


def _map_legend(recording: Recording, found: Analysis) -> str:
    counts = Counter(mark.kind for mark in marks(recording, found))
    swatches = _swatches((f"{name} ({counts[kind]})", colour) for kind, name, colour in _MARKS)
    return (
        f'<p class="legend">{colour_bar(recording.duration)} {swatches}<span>'
        "a number by a mark: that many, there; arrows: the heading; "
        "hover the path to see that moment on the timeline</span></p>"
    )


_ZOOM_BAR = (
    '<p class="zoombar"><button type="button" class="reset-zoom">reset zoom</button> '
    '<span class="view"></span> <span class="hint">wheel over the plots: zoom; drag: pan; '
    "double-click: reset; the wheel over the labels on the left scrolls the page</span></p>"
)


def _problem(recording: Recording) -> str:
    if recording.error is not None:
        return (
            f'<p class="error">{esc(recording.error)}: showing the '
            f"{len(recording.events)} events before it</p>"
        )
    if recording.end is None:
        return '<p class="error">the recording was not closed: the run may have crashed</p>'
    return ""


def page_title(recording: Recording, title: str | None = None) -> str:
    """The page's title: ``title``, else the recording's file name, else "pyrobots_aio run"."""
    if title:
        return title
    return Path(recording.path).name if recording.path else "pyrobots_aio run"


def render_timeline_html(recording: Recording, *, title: str | None = None) -> str:
    """Draw a recording as a self-contained HTML page: map, timeline, plots, rates.

    Args:
        recording: What to draw.
        title: The page title (default: the recording's file name, or "pyrobots_aio run").

    Returns:
        The page. Each action is a ``rect`` of class ``action`` plus its outcome
        (``succeeded`` ...), with a tooltip, and each spell it spent paused a
        ``rect.paused`` over it (hatched); resource holds are ``rect.hold``,
        waits ``rect.wait``, monitor firings ``line.firing``; on the map
        (``svg.map``), the path is ``polyline.trail`` and the marks
        ``path.mark``; the sensor plots are ``polyline.plot`` and
        ``polygon.plot.bool``. Lone surrogates from the recording are
        spelled out as backslash escapes, so that the page can be written as UTF-8.

    Examples:
        >>> from pyrobots_aio.recording import load, render_timeline_html
        >>> page = render_timeline_html(load("run.jsonl"))  # doctest: +SKIP
        >>> open("run.html", "w").write(page)  # doctest: +SKIP
    """
    found = analyse(recording)
    canvas = _Canvas(recording, found)
    _draw_actions(canvas)
    _draw_resources(canvas)
    _draw_firings(canvas)
    _draw_state(canvas, recording)
    _draw_plots(canvas, recording)
    heading = page_title(recording, title)
    arena = render_map(recording, found)
    where = ["<h2>Where the robot went</h2>", _map_legend(recording, found), arena] if arena else []
    page = "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            f"<title>{esc(heading)}</title><style>{_CSS}</style></head><body>",
            f"<h1>{esc(heading)}</h1>",
            _facts(recording),
            _problem(recording),
            *where,
            "<h2>Timeline of actions, resources and sensors</h2>",
            _legend(canvas),
            _ZOOM_BAR,
            canvas.svg(),
            "<h2>Actions started and events</h2>",
            rate_chart(recording, found, canvas.scale),
            '<div class="readout" hidden></div>',
            f"<script>{_SCRIPT}</script>",
            "</body></html>",
            "",
        ]
    )
    # A lone surrogate ("\ud800": valid JSON, not text) cannot be written as UTF-8: spelled out.
    return page.encode("utf-8", "backslashreplace").decode("utf-8")
