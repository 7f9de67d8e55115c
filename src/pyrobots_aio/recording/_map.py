"""The map of the replay page: the arena seen from above, the robot's path, what happened where.

Drawn from the recording alone: the arena from the header's floor plan (the
MuJoCo model's static geoms, recorded by a simulated robot's recorder), to
scale with a scale bar; the path from the recorded poses, coloured by time
(`_svg.ramp`), with arrows along it for the robot's heading; marks for bumps,
cliffs, preemptions, undocking, docking and the disturbances an exploration
dealt (the ``disturbance`` state key that `pyrobots_aio.testing.explore` writes
at each hit) at the pose of their moment. Marks of one kind closer than
`CLUSTER_PX` are drawn once with their count (a robot bumps into the same
corner again and again), and the kinds sit a little apart, so that none hides
another. Everything is in pixels: ``data-ox``, ``data-oy``
and ``data-scale`` on the ``svg.map`` give the map frame back
(``x = (px - ox) / scale``, ``y = (oy - py) / scale``), and ``data-track``
holds the path as ``t,x,y,yaw`` quadruples for the page's hover script, which
draws the robot's heading at the cursor's moment.

Coordinates are drawn within `REACH` of the origin: a pose beyond (a
simulation that blew up, a crafted file) is drawn at that distance, and a
floor-plan shape beyond is left out like any malformed shape, so that the
map's arithmetic stays finite (a pose at 1e308 m would make the scale 0).
"""

from __future__ import annotations

import bisect
import itertools
import math
from array import array
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from pyrobots_aio.telemetry import FloorShape

from . import _svg
from ._svg import esc

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from ._analysis import Analysis
    from ._recording import PoseTrack, Recording

SIZE = 560
"""Pixels of the longer side of the arena."""
MARGIN = 24
STEP_PX = 1.5
"""The path keeps a point once it is this many pixels from the last one kept."""
MAX_TRACK = 3000
"""Most ``t,x,y`` triples given to the hover script."""
REACH = 1e9
"""Metres from the origin drawn (see the module notes)."""
CLUSTER_PX = 10.0
"""Marks of one kind within this many pixels of a drawn one join it (and its count)."""
ARROW_EVERY_PX = 60.0
"""Pixels of path between two of its heading arrows."""
MAX_ARROWS = 60
ARROW = "M-4,-4 L3,0 L-4,4"
"""A chevron pointing along +x (the heading, once rotated)."""
ARROW_HEAD = "M9,-5 L15,0 L9,5"
"""The tip of the cursor's heading arrow, a line from the robot along +x."""


@dataclass(frozen=True, slots=True)
class Mark:
    """Something that happened at a moment, drawn where the robot was then."""

    kind: str
    time: float
    text: str


def _within_reach(poses: PoseTrack) -> PoseTrack:
    """``poses`` with each coordinate brought within `REACH` of the origin, each yaw within ±pi."""

    def near(values: Sequence[float]) -> array[float]:
        return array("d", [min(REACH, max(-REACH, value)) for value in values])

    yaw = array("d", [math.remainder(value, math.tau) for value in poses.yaw])
    return replace(poses, x=near(poses.x), y=near(poses.y), yaw=yaw)


def _reachable(shape: FloorShape) -> bool:
    """Whether ``shape`` lies within `REACH` of the origin (else it is left out)."""
    sizes = shape.half if shape.half is not None else (shape.radius or 0.0,)
    return all(abs(v) <= REACH for v in (shape.x, shape.y, *sizes))


def _corners(shape: FloorShape) -> list[tuple[float, float]] | None:
    """The corners of a box, in ``map``; None for a circle."""
    if shape.half is None:
        return None
    (hx, hy), c, s = shape.half, math.cos(shape.yaw), math.sin(shape.yaw)
    return [
        (shape.x + c * dx - s * dy, shape.y + s * dx + c * dy)
        for dx, dy in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))
    ]


def _extent(shapes: Sequence[FloorShape], recording: Recording) -> tuple[float, ...] | None:
    xs, ys = list(recording.poses.x), list(recording.poses.y)
    for shape in shapes:
        corners = _corners(shape)
        if corners is not None:
            xs += [c[0] for c in corners]
            ys += [c[1] for c in corners]
        else:
            radius = shape.radius or 0.0
            xs += [shape.x - radius, shape.x + radius]
            ys += [shape.y - radius, shape.y + radius]
    if not xs:
        return None
    return min(xs), min(ys), max(xs), max(ys)


class _Frame:
    """Map metres to pixels: x to the right, y up."""

    def __init__(self, extent: tuple[float, ...]) -> None:
        x0, y0, x1, y1 = extent
        span = max(x1 - x0, y1 - y0, 1e-3)
        self.scale = SIZE / span
        self.ox = MARGIN - x0 * self.scale
        self.oy = MARGIN + y1 * self.scale
        self.width = MARGIN * 2 + (x1 - x0) * self.scale
        self.height = MARGIN * 2 + (y1 - y0) * self.scale + 40  # the scale bar below

    def px(self, x: float, y: float) -> tuple[float, float]:
        return self.ox + x * self.scale, self.oy - y * self.scale


def _fill(shape: FloorShape) -> str:
    """The style attribute giving ``shape`` its colour, if it has one."""
    if shape.rgba is None:
        return ""
    r, g, b = (round(255 * min(1.0, max(0.0, v))) for v in shape.rgba[:3])
    return f' style="fill:#{r:02x}{g:02x}{b:02x}"'


def _draw_shape(frame: _Frame, shape: FloorShape) -> str:
    kind, fill = _svg.css_class(shape.kind, "obstacle"), _fill(shape)
    title = f"<title>{esc(shape.name)} ({esc(shape.kind)})</title>"
    corners = _corners(shape)
    if corners is not None:
        points = " ".join(f"{px:.1f},{py:.1f}" for px, py in (frame.px(*c) for c in corners))
        return f'<polygon class="shape {kind}" points="{points}"{fill}>{title}</polygon>'
    cx, cy = frame.px(shape.x, shape.y)
    r = (shape.radius or 0.0) * frame.scale
    circle = f'<circle class="shape {kind}" cx="{cx:.1f}" cy="{cy:.1f}" r="{r:.1f}"'
    return f"{circle}{fill}>{title}</circle>"


def _kept(frame: _Frame, recording: Recording) -> list[int]:
    """Indices of the poses drawn: each at least `STEP_PX` from the one before, and the last."""
    poses, kept = recording.poses, []
    last_x = last_y = math.inf
    limit = (STEP_PX / frame.scale) ** 2
    for i, (x, y) in enumerate(zip(poses.x, poses.y, strict=True)):
        if (x - last_x) ** 2 + (y - last_y) ** 2 >= limit:
            kept.append(i)
            last_x, last_y = x, y
    if kept and kept[-1] != len(poses) - 1:
        kept.append(len(poses) - 1)
    return kept


def _trail(frame: _Frame, recording: Recording, kept: list[int]) -> list[str]:
    """The path as polylines of about 2 pixels of colour each, coloured by time."""
    poses = recording.poses
    start, duration = recording.start, recording.duration or 1.0
    pieces = max(1, min(len(kept) - 1, 240))
    per = (len(kept) - 1) / pieces
    parts = ['<g class="trail">']
    for piece in range(pieces):
        chunk = kept[round(piece * per) : round((piece + 1) * per) + 1]
        if len(chunk) < 2:
            continue
        points = " ".join("{:.1f},{:.1f}".format(*frame.px(poses.x[i], poses.y[i])) for i in chunk)
        t0, t1 = poses.times[chunk[0]] - start, poses.times[chunk[-1]] - start
        colour = _svg.ramp(((t0 + t1) / 2) / duration)
        parts.append(
            f'<polyline class="trail" points="{points}" style="stroke:{colour}" '
            f'data-t0="{t0:.3f}" data-t1="{t1:.3f}"><title>{t0:.1f} to {t1:.1f} s</title>'
            "</polyline>"
        )
    parts.append("</g>")
    return parts


def _rising(times: Sequence[float], values: Sequence[object]) -> Iterable[tuple[float, bool]]:
    """Each change of a boolean series after its first value: (time, new value)."""
    previous: object = None
    for i, (time, value) in enumerate(zip(times, values, strict=True)):
        if i and isinstance(value, bool) and value is not previous:
            yield time, value
        previous = value


def marks(recording: Recording, found: Analysis) -> list[Mark]:
    """Bumps, cliffs, preemptions, undocking, docking and disturbances, in time order."""
    found_marks: list[Mark] = []
    bumper = recording.samples.get("bumper")
    if bumper is not None:
        sides = ("bumper_left", "bumper_right")
        for time, value in _rising(bumper.times, bumper.values):
            if value:
                hit = [s.removeprefix("bumper_") for s in sides if _value_at(recording, s, time)]
                found_marks.append(Mark("bump", time, f"bump ({' and '.join(hit) or 'bumper'})"))
    for key, series in recording.samples.items():
        if key.startswith("cliff_"):
            found_marks += [
                Mark("cliff", t, f"cliff: {key}")
                for t, v in _rising(series.times, series.values)
                if v
            ]
    docked = recording.samples.get("docked")
    if docked is not None:
        found_marks += [
            Mark("dock" if v else "undock", t, "docked" if v else "undocked")
            for t, v in _rising(docked.times, docked.values)
        ]
    dealt = recording.samples.get("disturbance")
    if dealt is not None:
        found_marks += [
            Mark("disturbance", t, f"disturbance: {v}")
            for t, v in zip(dealt.times, dealt.values, strict=True)
        ]
    for event in found.preemptions:
        victim = found.label(event.action) or "?"
        found_marks.append(
            Mark("preempt", event.time, f"{victim} preempted for {event.resource!r}")
        )
    return sorted(found_marks, key=lambda m: m.time)


def _value_at(recording: Recording, key: str, time: float) -> object:
    series = recording.samples.get(key)
    if series is None:
        return None
    i = bisect.bisect_right(series.times, time) - 1
    return series.values[i] if i >= 0 else None


def _pose_at(recording: Recording, time: float) -> tuple[float, float] | None:
    poses = recording.poses
    i = bisect.bisect_right(poses.times, time) - 1
    if not len(poses):
        return None
    i = max(0, i)
    return poses.x[i], poses.y[i]


_SYMBOLS = {
    "bump": "M-6,-6 L6,6 M-6,6 L6,-6",
    "cliff": "M0,-7 L7,6 L-7,6 Z",
    "preempt": "M-5,-7 h10 l-5,8 z",
    "dock": "M-5,-5 h10 v10 h-10 z",
    "undock": "M-5,-5 h10 v10 h-10 z",
    "disturbance": "M0,-8 L8,0 L0,8 L-8,0 Z",
}
_OFFSETS = {
    "bump": (0, 0),
    "cliff": (-9, 9),
    "preempt": (9, -9),
    "dock": (0, 0),
    "undock": (9, 9),
    "disturbance": (-9, -9),
}
"""Where each kind sits from the robot, in pixels: a preemption at a bump stays in sight."""
MAX_LISTED = 8
"""Most moments a mark's tooltip lists."""


@dataclass(slots=True)
class _Cluster:
    """Marks of one kind drawn as one, at the place of the first."""

    kind: str
    px: float
    py: float
    marks: list[Mark]


def _clusters(placed: Iterable[tuple[Mark, float, float]]) -> list[_Cluster]:
    """Group marks of a kind within `CLUSTER_PX` of a group's first, in time order.

    Groups are found through a grid of `CLUSTER_PX` cells (a mark looks in its
    cell and the eight around it), so that thousands of marks stay linear.
    """
    grid: dict[tuple[str, int, int], list[_Cluster]] = {}
    found: list[_Cluster] = []
    for mark, px, py in placed:
        i, j = math.floor(px / CLUSTER_PX), math.floor(py / CLUSTER_PX)
        near = (
            c
            for di in (-1, 0, 1)
            for dj in (-1, 0, 1)
            for c in grid.get((mark.kind, i + di, j + dj), ())
            if math.hypot(c.px - px, c.py - py) <= CLUSTER_PX
        )
        cluster = next(near, None)
        if cluster is None:
            cluster = _Cluster(mark.kind, px, py, [])
            grid.setdefault((mark.kind, i, j), []).append(cluster)
            found.append(cluster)
        cluster.marks.append(mark)
    return found


def _cluster_title(cluster: _Cluster, start: float) -> str:
    listed = [f"{m.text} at {m.time - start:.3f} s" for m in cluster.marks[:MAX_LISTED]]
    more = len(cluster.marks) - MAX_LISTED
    if more > 0:
        listed.append(f"and {more} more")
    if len(cluster.marks) > 1:
        listed.insert(0, f"{len(cluster.marks)} times here:")
    return "\n".join(listed)


def _draw_marks(frame: _Frame, recording: Recording, found: Analysis) -> list[str]:
    parts = ['<g class="marks">']
    start = recording.start
    placed = [
        (mark, *frame.px(*where))
        for mark in marks(recording, found)
        if (where := _pose_at(recording, mark.time)) is not None
    ]
    for cluster in _clusters(placed):
        dx, dy = _OFFSETS[cluster.kind]
        px, py, count = cluster.px + dx, cluster.py + dy, len(cluster.marks)
        parts.append(
            f'<path class="mark {cluster.kind}" transform="translate({px:.1f},{py:.1f})" '
            f'd="{_SYMBOLS[cluster.kind]}" data-t="{cluster.marks[0].time - start:.3f}" '
            f'data-count="{count}"><title>{esc(_cluster_title(cluster, start))}</title></path>'
        )
        if count > 1:
            parts.append(f'<text class="count" x="{px + 7:.1f}" y="{py - 5:.1f}">{count}</text>')
    parts.append("</g>")
    return parts


def _headings(frame: _Frame, recording: Recording, kept: list[int]) -> list[str]:
    """Chevrons along the path, every `ARROW_EVERY_PX` pixels, pointing where the robot faced."""
    poses, start = recording.poses, recording.start
    places = [frame.px(poses.x[i], poses.y[i]) for i in kept]
    steps = [math.dist(a, b) for a, b in itertools.pairwise(places)]
    every = max(ARROW_EVERY_PX, sum(steps) / MAX_ARROWS)
    parts, travelled = ['<g class="headings">'], 0.0
    for i, (px, py), step in zip(kept[1:], places[1:], steps, strict=True):
        travelled += step
        if travelled < every:
            continue
        travelled = 0.0
        yaw = math.degrees(poses.yaw[i])
        parts.append(
            f'<path class="heading" transform="translate({px:.1f},{py:.1f}) rotate({-yaw:.0f})" '
            f'd="{ARROW}"><title>heading {yaw:.0f} degrees at {poses.times[i] - start:.1f} s'
            "</title></path>"
        )
    parts.append("</g>")
    return parts


def _scale_bar(frame: _Frame) -> str:
    metres = _svg.nice_step(SIZE / frame.scale, 4)
    length = metres * frame.scale
    y = frame.height - 22
    return (
        f'<g class="scalebar"><line x1="{MARGIN}" y1="{y:.1f}" x2="{MARGIN + length:.1f}" '
        f'y2="{y:.1f}"/><line x1="{MARGIN}" y1="{y - 4:.1f}" x2="{MARGIN}" y2="{y + 4:.1f}"/>'
        f'<line x1="{MARGIN + length:.1f}" y1="{y - 4:.1f}" x2="{MARGIN + length:.1f}" '
        f'y2="{y + 4:.1f}"/><text x="{MARGIN + length + 6:.1f}" y="{y + 4:.1f}">{metres:g} m</text>'
        "</g>"
    )


def _track(recording: Recording, kept: list[int]) -> str:
    poses, start = recording.poses, recording.start
    every = max(1, math.ceil(len(kept) / MAX_TRACK))
    picked = kept[::every]
    if kept and picked[-1] != kept[-1]:
        picked.append(kept[-1])
    return ";".join(
        f"{poses.times[i] - start:.3f},{poses.x[i]:.4f},{poses.y[i]:.4f},{poses.yaw[i]:.3f}"
        for i in picked
    )


def render_map(recording: Recording, found: Analysis) -> str:
    """The map's SVG, or "" when the recording has neither a floor plan nor poses."""
    shapes = [s for s in FloorShape.read_plan(recording.header.floor_plan) if _reachable(s)]
    recording = replace(recording, poses=_within_reach(recording.poses))
    extent = _extent(shapes, recording)
    if extent is None:
        return ""
    frame = _Frame(extent)
    kept = _kept(frame, recording)
    parts = ['<g class="arena">', *(_draw_shape(frame, s) for s in shapes), "</g>"]
    parts += _trail(frame, recording, kept)
    parts += _headings(frame, recording, kept)
    parts += _draw_marks(frame, recording, found)
    if kept:
        px, py = frame.px(recording.poses.x[kept[0]], recording.poses.y[kept[0]])
        parts.append(
            f'<circle class="start" cx="{px:.1f}" cy="{py:.1f}" r="4"><title>start</title></circle>'
        )
    parts.append('<circle class="here" cx="-99" cy="-99" r="7"/>')
    parts.append(
        f'<path class="here-heading" transform="translate(-99,-99)" d="M0,0 h14 {ARROW_HEAD}"/>'
    )
    parts.append(_scale_bar(frame))
    return (
        f'<svg class="map" xmlns="http://www.w3.org/2000/svg" '
        f'viewBox="0 0 {frame.width:.0f} {frame.height:.0f}" width="{frame.width:.0f}" '
        f'height="{frame.height:.0f}" data-ox="{frame.ox:.4f}" data-oy="{frame.oy:.4f}" '
        f'data-scale="{frame.scale:.6f}" data-track="{_track(recording, kept)}">'
        + "".join(parts)
        + "</svg>"
    )


def colour_bar(duration: float) -> str:
    """The legend of the path's colours: start to end of the run."""
    stops = "".join(f'<i style="background:{_svg.ramp(i / 9)}"></i>' for i in range(10))
    return f'<span class="ramp">path: 0 s {stops} {duration:.0f} s</span>'
