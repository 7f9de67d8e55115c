"""`render_timeline_html`: the two figures of the pyRobots paper, as one self-contained page.

Figure 1, the timeline: one row per action *path* (an action name under its
parent's row, so children sit indented under their parents), each instance a
bar from its start to its end coloured by outcome, with a tooltip giving the
parent, the outcome and, for a cancelled action, who cancelled it and why.
Instances of one path that overlap take extra lanes. Below: each resource's
holds (coloured by holder), waits, preemptions; monitor firings; boolean state.

Figure 2: actions started and events (monitor firings) per minute, in buckets
of a width chosen for the run's length.

Plain HTML, inline CSS and SVG; no script, no external asset.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

from pyrobots_aio import EventKind

from . import _svg
from ._analysis import Analysis, Interval, Span, analyse
from ._chart import rate_chart
from ._summary import summarize
from ._svg import AXIS_H, BAR_H, ROW_H, WIDTH, Scale, esc

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from ._recording import Recording

T = TypeVar("T")

_CSS = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 24px; color: #212121; }
h1 { font-size: 20px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 24px 0 6px; }
.facts { color: #555; margin: 0 0 8px; } .error { color: #b71c1c; font-weight: 600; }
svg { width: 100%; max-width: 1200px; height: auto; display: block; }
svg text { font: 11px sans-serif; fill: #333; } .section { font-weight: 700; }
.grid { stroke: #e0e0e0; stroke-width: 1; } rect { stroke: #fff; stroke-width: 0.5; }
rect:hover { stroke: #000; stroke-width: 1; } text.in { fill: #fff; pointer-events: none; }
text.in.dark { fill: #37474f; }
.succeeded { fill: #43a047; } .failed { fill: #e53935; } .cancelled { fill: #fb8c00; }
.skipped { fill: #9e9e9e; } .not_done { fill: #1e88e5; }
.wait { fill: #cfd8dc; } .state-on { fill: #7e57c2; } .cancel-mark { stroke: #000; }
.preempt { fill: #b71c1c; } .firing { stroke: #6a1b9a; stroke-width: 2; }
.rate-actions { fill: #1e88e5; } .rate-events { fill: #8e24aa; }
.legend span { display: inline-block; margin-right: 14px; }
.legend i { display: inline-block; width: 12px; height: 12px; margin-right: 4px;
  vertical-align: -1px; }
"""


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
    for child in node.children.values():  # insertion order: first spawned first
        yield child
        yield from _walk(child)


def _lanes(
    items: Sequence[T], begin: Callable[[T], float], end: Callable[[T], float]
) -> list[list[T]]:
    """Pack intervals into lanes so that no two in a lane overlap (first fit, by start)."""
    lanes: list[list[T]] = []
    free_at: list[float] = []
    for item in sorted(items, key=begin):
        b = begin(item)
        for i, t in enumerate(free_at):
            if t <= b:
                lanes[i].append(item)
                free_at[i] = end(item)
                break
        else:
            lanes.append([item])
            free_at.append(end(item))
    return lanes


class _Canvas:
    """The timeline figure being drawn, top to bottom."""

    def __init__(self, recording: Recording, found: Analysis) -> None:
        self.scale = Scale(recording.start, recording.duration)
        self.start, self.stop = recording.start, recording.stop
        self.found = found
        self.parts: list[str] = []
        self.y = float(AXIS_H)
        self._hues: dict[str, str] = {}

    def hue(self, name: str) -> str:
        """The colour of resource holds by actions called ``name`` (one per name)."""
        colour = self._hues.get(name)
        if colour is None:
            colour = self._hues[name] = _svg.hue(len(self._hues))
        return colour

    def end_of(self, span: Span) -> float:
        """When ``span`` finished, or the end of the recording if it had not."""
        return span.finished if span.finished is not None else self.stop

    def rel(self, time: float) -> str:
        return f"{time - self.start:.3f}"

    def section(self, title: str) -> None:
        self.y += 6
        self.parts.append(_svg.label(title, self.y, cls="section"))
        self.y += ROW_H

    def bar(
        self, cls: str, begin: float, end: float, title: str, *, text: str = "", fill: str = ""
    ) -> None:
        """A bar on the current row, with a tooltip and, if it fits, ``text`` inside."""
        x, w = self.scale.x(begin), self.scale.width(begin, end)
        self.parts.append(_svg.rect(cls, (x, self.y, w, BAR_H), title, fill))
        fits = int((w - 4) // _svg.CHAR_W)
        if text and fits >= 3:
            shown = text if len(text) <= fits else text[: fits - 1] + "\u2026"
            ink = "in dark" if cls == "wait" else "in"
            y = self.y + BAR_H - 3
            self.parts.append(
                f'<text class="{ink}" x="{x + 2:.1f}" y="{y:.1f}">{esc(shown)}</text>'
            )

    def tick(self, cls: str, time: float, title: str) -> None:
        x = self.scale.x(time)
        self.parts.append(
            f'<line class="{cls}" x1="{x:.1f}" y1="{self.y:.1f}" x2="{x:.1f}" '
            f'y2="{self.y + BAR_H:.1f}"><title>{esc(title)}</title></line>'
        )

    def svg(self) -> str:
        height = self.y + 8
        axis = _svg.time_axis(self.scale, height)
        return (
            f'<svg class="timeline" xmlns="http://www.w3.org/2000/svg" '
            f'viewBox="0 0 {WIDTH} {height:.0f}" width="{WIDTH}" height="{height:.0f}">'
            + "".join(axis + self.parts)
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
    return "\n".join(lines)


def _begin(span: Span) -> float:
    return span.begin


def _draw_actions(canvas: _Canvas) -> None:
    canvas.section("actions")
    for node in _walk(_tree(canvas.found)):
        canvas.parts.append(_svg.label(f"{node.name} x{len(node.spans)}", canvas.y, node.depth))
        for lane in _lanes(node.spans, _begin, canvas.end_of):
            for span in lane:
                title = _action_title(canvas, span)
                end = canvas.end_of(span)
                label = f"{span.name}#{span.id}"
                canvas.bar(f"action {span.outcome}", span.begin, end, title, text=label)
                if span.cancelled_at is not None:
                    canvas.tick(
                        "cancel-mark", span.cancelled_at, f"cancel requested: {span.reason}"
                    )
            canvas.y += ROW_H


def _interval_rows(canvas: _Canvas, intervals: list[Interval], cls: str, what: str) -> None:
    ends = [i.end if i.end is not None else canvas.stop for i in intervals]
    index = {id(i): e for i, e in zip(intervals, ends, strict=True)}
    for lane in _lanes(intervals, lambda i: i.start, lambda i: index[id(i)]):
        for i in lane:
            end = index[id(i)]
            title = (
                f"{i.resource} {what} {i.name}#{i.action} (priority {i.priority})\n"
                f"{canvas.rel(i.start)} -> {canvas.rel(end)} s ({end - i.start:.3f} s)"
                + ("" if i.outcome == "held" else f", {i.outcome.replace('_', ' ')}")
            )
            fill = canvas.hue(i.name) if cls == "hold" else ""
            canvas.bar(cls, i.start, end, title, text=f"{i.name}#{i.action}", fill=fill)
        canvas.y += ROW_H


def _draw_resources(canvas: _Canvas) -> None:
    found = canvas.found
    names = sorted({i.resource for i in found.holds} | {i.resource for i in found.waits})
    if not names:
        return
    canvas.section("resources")
    for name in names:
        canvas.parts.append(_svg.label(name, canvas.y, 1))
        top = canvas.y
        _interval_rows(canvas, [h for h in found.holds if h.resource == name], "hold", "held by")
        for event in found.preemptions:
            if event.data.get("resource") == name:
                x = canvas.scale.x(event.time)
                canvas.parts.append(
                    f'<path class="preempt" d="M{x - 5:.1f},{top:.1f} h10 l-5,7 z">'
                    f"<title>{esc(event.data.get('reason'))}</title></path>"
                )
        waits = [w for w in found.waits if w.resource == name]
        if waits:
            canvas.parts.append(_svg.label("waiting", canvas.y, 2))
            _interval_rows(canvas, waits, "wait", "awaited by")


def _draw_firings(canvas: _Canvas) -> None:
    names = sorted({e.name or "?" for e in canvas.found.firings})
    if not names:
        return
    canvas.section("monitor firings")
    for name in names:
        canvas.parts.append(_svg.label(name, canvas.y, 1))
        for event in canvas.found.firings:
            if (event.name or "?") == name:
                canvas.tick("firing", event.time, f"{name} fired at {canvas.rel(event.time)} s")
        canvas.y += ROW_H


def _state_spans(recording: Recording) -> dict[str, list[tuple[float, float]]]:
    """For each boolean state key sampled: the intervals during which it was true."""
    spans: dict[str, list[tuple[float, float]]] = {}
    since: dict[str, float | None] = {}
    for event in recording.events:
        value = event.data.get("value")
        if event.kind is not EventKind.STATE_SAMPLE or not isinstance(value, bool):
            continue
        key = event.name or "?"
        spans.setdefault(key, [])
        began = since.get(key)
        if value and began is None:
            since[key] = event.time
        elif not value and began is not None:
            spans[key].append((began, event.time))
            since[key] = None
    for key, began in since.items():
        if began is not None:
            spans[key].append((began, recording.stop))
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
            canvas.bar("state-on", begin, end, title)
        canvas.y += ROW_H


def _facts(recording: Recording) -> str:
    summary = summarize(recording)
    o = summary.outcomes
    robot = esc(summary.robot or "unknown robot")
    seed = f", seed {summary.seed}" if summary.seed is not None else ""
    return (
        f'<p class="facts">{robot}{seed} &middot; {summary.duration:.3f} s &middot; '
        f"{summary.actions} actions ({o.succeeded} succeeded, {o.failed} failed, "
        f"{o.cancelled} cancelled, {o.skipped} skipped, {o.not_done} not done) &middot; "
        f"peak concurrency {summary.peak_concurrency} &middot; "
        f"{summary.mean_actions_per_minute:.1f} actions and "
        f"{summary.mean_events_per_minute:.1f} events per minute</p>"
    )


def _legend() -> str:
    swatches = [(name.replace("_", " "), colour) for name, colour in _svg.OUTCOME_COLOURS.items()]
    swatches += [("waiting for a resource", "#cfd8dc"), ("state true", "#7e57c2")]
    items = "".join(
        f'<span><i style="background:{colour}"></i>{text}</span>' for text, colour in swatches
    )
    return f'<p class="legend">{items}</p>'


def _problem(recording: Recording) -> str:
    if recording.error is not None:
        return (
            f'<p class="error">{esc(recording.error)}: showing the '
            f"{len(recording.events)} events before it</p>"
        )
    if recording.end is None:
        return '<p class="error">the recording was not closed: the run may have crashed</p>'
    return ""


def render_timeline_html(recording: Recording, *, title: str | None = None) -> str:
    """Draw a recording as a self-contained HTML page (inline SVG and CSS, no script).

    Args:
        recording: What to draw.
        title: The page title (default: the recording's file name, or "pyrobots_aio run").

    Returns:
        The page. Each action is a ``rect`` of class ``action`` plus its outcome
        (``succeeded`` ...), with a tooltip; resource holds are ``rect.hold``,
        waits ``rect.wait``, monitor firings ``line.firing``.

    Example:
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
    heading = title or recording.path or "pyrobots_aio run"
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            f"<title>{esc(heading)}</title><style>{_CSS}</style></head><body>",
            f"<h1>{esc(heading)}</h1>",
            _facts(recording),
            _problem(recording),
            _legend(),
            "<h2>Timeline of actions and resources</h2>",
            canvas.svg(),
            "<h2>Actions and events per minute</h2>",
            rate_chart(recording, found),
            "</body></html>",
            "",
        ]
    )
