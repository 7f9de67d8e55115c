"""Untrusted recordings (issues 16 and 26): escaped everywhere, safe and bounded to read.

The crafted files are written in the version 1 format (state samples as
``state.sample`` events), which this library still reads, so that the same
tests run against the code before the fixes and fail there.
"""

from __future__ import annotations

import asyncio
import html.parser
import json
import math
import re
import tracemalloc
from typing import TYPE_CHECKING, Any, TypeVar

import pytest

from pyrobots_aio import (
    ActionSpawned,
    ActionStarted,
    CorruptRecordingError,
    ExecEvent,
    MonitorFired,
    ResourceAcquired,
    Robot,
    action,
)
from pyrobots_aio.recording import (
    JsonlRecorder,
    Recording,
    RecordingHeader,
    format_summary,
    load,
    render_timeline_html,
    summarize,
)

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

T = TypeVar("T")

HOSTILE = "x\"><script>alert(1)</script><img src=x onerror=alert(2)>'&"
"""Breaks out of an attribute (either quote), then of the text: a script and a handler."""
TAGS = {
    "html", "head", "meta", "title", "style", "body", "h1", "h2", "p", "span", "i", "svg",
    "g", "text", "rect", "line", "path", "polyline", "polygon", "circle", "script", "defs",
    "pattern", "button", "div",
}  # fmt: skip
CLASS = re.compile(r"^[a-z_][a-z0-9_ -]*$")
DEEP = 1500
"""Nested actions: deeper than Python's recursion limit."""


def _header(**fields: Any) -> dict[str, Any]:
    header = {"format": "pyrobots_aio.recording", "version": 1, "t0": 0.0}
    return {**header, **fields}


def _write(path: Path, header: dict[str, Any], *records: dict[str, Any], end: float = 9.0) -> None:
    lines = [header, *records, {"end": end, "events": len(records)}]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))


def _event(t: float, kind: str, action: int | None, name: str, **data: object) -> dict[str, Any]:
    return {"t": t, "action": action, "kind": kind, "name": name, "data": data}


def _hostile_run() -> list[dict[str, Any]]:
    h = HOSTILE
    leaves = {"resources": [h], "leaves": [h], "priority": h}
    return [
        _event(0.0, "action.spawned", 1, h, parent=h),
        _event(0.0, "action.started", 1, h),
        _event(0.0, "resource.acquired", 1, h, **leaves),
        _event(0.5, "action.spawned", 2, h + "2", parent=1),
        _event(0.5, "resource.waiting", 2, h + "2", **leaves),
        _event(0.6, "action.paused", 1, h, reason=h, by=h, paused=h),
        _event(0.6, "action.paused", 2, h + "2", reason=h, by=1, paused=1),
        _event(0.8, "action.resumed", 2, h + "2", resumed=h),
        _event(1.0, "resource.preempted", 1, h, resource=h, by=2, reason=h, **leaves),
        _event(1.0, "action.cancel_requested", 1, h, reason=h, by=h),
        _event(1.0, "resource.released", 1, h, **leaves),
        _event(1.0, "action.finished", 1, h, outcome=h, error=h),
        _event(1.0, "resource.acquired", 2, h + "2", **leaves),
        _event(2.0, "monitor.fired", None, h, callback=h),
        _event(2.0, "state.sample", None, h, value=True),
        _event(2.0, "state.sample", None, "bumper", value=True),
        _event(2.5, "state.sample", None, h, value=False),
        _event(3.0, "state.sample", None, "v", value=h),
        _event(4.0, "action.finished", 2, h + "2", outcome="failed", error=h),
    ]


class _Page(html.parser.HTMLParser):
    """Every tag with its attributes, and the text of the scripts."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.scripts: list[str] = []
        self._in_script = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))
        self._in_script = tag == "script"

    def handle_endtag(self, tag: str) -> None:
        self._in_script = False

    def handle_data(self, data: str) -> None:
        if self._in_script:
            self.scripts.append(data)


def test_hostile_strings_in_every_field_stay_text(tmp_path: Path) -> None:
    path = tmp_path / f"{HOSTILE.replace('/', '_')}.jsonl"
    plan = [{"name": HOSTILE, "kind": HOSTILE, "shape": "box", "x": 0, "y": 0, "half": [1, 1]}]
    plan[0]["rgba"] = [HOSTILE, 0, 0, 1]
    _write(path, _header(robot=HOSTILE, metadata={"a": HOSTILE}, floor_plan=plan), *_hostile_run())
    recording = load(path)
    for page in (render_timeline_html(recording), render_timeline_html(recording, title=HOSTILE)):
        parsed = _Page()
        parsed.feed(page)
        assert {tag for tag, _ in parsed.tags} <= TAGS
        assert sum(1 for tag, _ in parsed.tags if tag == "script") <= 1
        assert all("alert" not in script for script in parsed.scripts)
        for tag, attrs in parsed.tags:
            assert not [name for name in attrs if name.startswith("on") or name == "src"], tag
            assert CLASS.match(attrs.get("class") or "x"), (tag, attrs)
            style = attrs.get("style") or ""
            assert not re.search("alert|script", style), (tag, style)
        assert "<script>alert" not in page
        assert HOSTILE not in page  # only ever escaped
        assert page.count('<rect class="paused"') == 2  # the pause reasons are on the page


def test_control_characters_from_a_recording_are_not_printed_raw(tmp_path: Path) -> None:
    path = tmp_path / "escape.jsonl"
    evil = "\x1b[2J\x1b[31mdrive\nforged line\x07\x9b"
    run = [
        _event(0.0, "action.spawned", 1, evil, parent=None),
        _event(0.0, "action.started", 1, evil),
        _event(1.0, "action.cancel_requested", 1, evil, reason=evil, by=None),
        _event(1.0, "action.finished", 1, evil, outcome="failed", error=evil),
        _event(1.0, "monitor.fired", None, evil),
        _event(1.0, "resource.acquired", 1, evil, resources=[evil], leaves=[evil], priority=0),
    ]
    _write(path, _header(robot=evil), *run)
    report = format_summary(summarize(load(path)))
    assert not set(report) & {"\x1b", "\x07", "\x9b"}
    assert not [line for line in report.splitlines() if line.startswith("forged")]
    assert "\\x1b[2J\\x1b[31mdrive\\x0aforged line\\x07\\x9b" in report


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ('{"t": NaN, "kind": "monitor.fired"}', "NaN is not a number a recording may hold"),
        ('{"t": 1e400, "kind": "monitor.fired"}', "the number 1e400 is out of range"),
        ('{"t": -Infinity, "kind": "monitor.fired"}', "-Infinity is not a number a recording"),
        ('{"kind": "monitor.fired", "t": ' + "9" * 500 + "}", "an integer of 500 digits"),
        ("[" * 100_000 + "]" * 100_000, "not valid JSON: nested too deeply"),
    ],
)
def test_non_finite_huge_or_deep_values_are_a_clear_error(
    tmp_path: Path, text: str, problem: str
) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text(json.dumps(_header()) + "\n" + text + "\n")
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert info.value.line == 2
    assert problem in str(info.value)


def test_a_non_finite_header_is_a_clear_error(tmp_path: Path) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text('{"format": "pyrobots_aio.recording", "version": 1, "t0": NaN}\n')
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert (
        str(info.value)
        == f"{path}:1: NaN is not a number a recording may hold (only finite numbers)"
    )


def test_memory_follows_the_events_not_the_time_span(tmp_path: Path) -> None:
    path = tmp_path / "long.jsonl"  # 300 bytes that span 1e18 s
    run = [
        _event(0.0, "action.spawned", 1, "a", parent=None),
        _event(1e18, "monitor.fired", None, "m"),
    ]
    _write(path, _header(), *run, end=1e18)
    tracemalloc.start()
    try:
        recording = load(path)
        summary = summarize(recording)
        page = render_timeline_html(recording)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 20_000_000
    assert summary.duration == 1e18
    assert (sum(summary.actions_per_minute), sum(summary.events_per_minute)) == (1, 1)
    assert "1.0 actions" not in format_summary(summary)  # per minute over 1e18 s: 0.0
    assert page.count('<rect class="rate-actions"') <= 60


@action
async def nest(robot: Robot, depth: int) -> int:
    return 1 + (await nest(robot, depth - 1) if depth > 1 else 0)


def test_the_library_s_own_recording_of_a_deep_action_tree_is_drawn(tmp_path: Path) -> None:
    path = tmp_path / "deep.jsonl"

    async def main() -> int:
        robot = Robot()
        with JsonlRecorder(path).attach(robot):
            async with robot:
                return await nest(robot, DEEP)

    assert asyncio.run(main()) == DEEP  # runs fine; the replay died with RecursionError
    recording = load(path)
    summary = summarize(recording)
    page = render_timeline_html(recording)
    assert (summary.actions, summary.outcomes.succeeded) == (DEEP, DEEP)
    assert page.count('<rect class="action succeeded"') == DEEP
    assert page.count(">nest x1</text>") == DEEP  # one row per level


def test_coordinates_beyond_reach_are_drawn_at_its_edge(tmp_path: Path) -> None:
    path = tmp_path / "far.jsonl"
    plan = [
        {"name": "far", "shape": "box", "x": 1e308, "y": 0, "half": [1e308, 1]},
        {"name": "wide", "shape": "circle", "x": 0, "y": 0, "radius": 1e308},
        {"name": "wall", "shape": "box", "x": 0, "y": 0, "half": [1, 1]},
    ]
    samples = [
        {"t": 0.0, "state": {"v": 1e308, "w": -1e308}, "pose": [1e308, -1e308, 1e308]},
        {"t": 1.0, "state": {"v": -1e308, "w": 1e308}, "pose": [-1e308, 1e308, -1e308]},
    ]
    _write(path, _header(floor_plan=plan), *samples, end=2.0)
    page = render_timeline_html(load(path))  # was ZeroDivisionError
    assert not re.search(r'[=", ](-?inf|nan)\b', page)
    assert page.count('<polygon class="shape') == 1  # the wall; the others are beyond reach
    track = re.search(r'data-track="([^"]*)"', page)
    assert track is not None
    yaw = math.remainder(1e308, math.tau)  # headings are drawn as turns within ±pi
    assert -math.pi <= yaw <= math.pi
    assert track.group(1) == (
        f"0.000,1000000000.0000,-1000000000.0000,{yaw:.3f};"
        f"1.000,-1000000000.0000,1000000000.0000,{-yaw:.3f}"
    )
    plots = re.findall(r'<polyline class="plot" points="([^"]*)" data-key="(\w)"', page)
    assert [key for _, key in plots] == ["v", "w"]
    for points, key in plots:  # from one edge of the plot to the other
        y = [float(point.split(",")[1]) for point in points.split()]
        assert (y[0], y[2] - y[0], y[3]) == (y[1], 40.0 if key == "v" else -40.0, y[2])


@pytest.mark.parametrize(
    ("header", "record", "line", "problem"),
    [
        (
            {"t0": -1.7e308},
            _event(1.7e308, "monitor.fired", None, "m"),
            1,
            "bad header: 't0' is out of range: -1.7e+308 (loop times are within ±1e+18 s)",
        ),
        (
            {},
            _event(1.7e308, "monitor.fired", None, "m"),
            2,
            "'t' is out of range: 1.7e+308 (loop times are within ±1e+18 s)",
        ),
        (
            {},
            {"t": -1e19, "state": {"v": 1.0}},
            2,
            "'t' is out of range: -1e+19 (loop times are within ±1e+18 s)",
        ),
    ],
)
def test_loop_times_beyond_the_range_are_a_clear_error(
    tmp_path: Path, header: dict[str, Any], record: dict[str, Any], line: int, problem: str
) -> None:
    path = tmp_path / "far.jsonl"
    _write(path, _header(**header), record, end=1.0)
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert str(info.value) == f"{path}:{line}: {problem}"


def test_an_end_beyond_the_range_is_a_clear_error(tmp_path: Path) -> None:
    path = tmp_path / "far.jsonl"
    _write(path, _header(), end=1.7e308)
    with pytest.raises(CorruptRecordingError) as info:
        load(path)
    assert str(info.value) == (
        f"{path}:2: 'end' is out of range: 1.7e+308 (loop times are within ±1e+18 s)"
    )


def test_lone_surrogates_are_escaped_in_the_report_and_the_page(tmp_path: Path) -> None:
    path = tmp_path / "odd.jsonl"
    run = [
        _event(0.0, "action.spawned", 1, "\ud800", parent=None),
        _event(0.5, "resource.acquired", 1, "\ud800", resources=["\udc00"], leaves=["\udc00"]),
        _event(1.0, "action.finished", 1, "\ud800", outcome="failed", error="\udfff"),
    ]
    plan = [{"name": "\ud800", "shape": "box", "x": 0, "y": 0, "half": [1, 1]}]
    _write(path, _header(robot="\ud800", floor_plan=plan), *run)
    recording = load(path)
    report = format_summary(summarize(recording))
    page = render_timeline_html(recording, title="\ud800")
    for text in (report, page):
        text.encode("utf-8")  # was UnicodeEncodeError
    assert report.startswith("\\ud800: 9.000 s recorded")
    assert "1.000 s  \\ud800#1: \\udfff" in report
    assert "<title>\\ud800</title>" in page
    assert "\\udc00" in page


class _Compared:
    """How often the values of `_counted` classes were compared."""

    times = 0


def _counted(base: type[T]) -> type[T]:
    """A subclass of ``base`` whose values count their comparisons in `_Compared`."""

    def counting(name: str) -> Callable[[object, object], object]:
        compare = getattr(base, name)

        def counted(self: object, other: object) -> object:
            _Compared.times += 1
            return compare(self, other)

        return counted

    names = ("__eq__", "__lt__", "__le__", "__gt__", "__ge__")
    methods = {name: counting(name) for name in names}
    return type(f"Counted{base.__name__}", (base,), {"__hash__": base.__hash__, **methods})


_Name = _counted(str)
_Time = _counted(float)
MANY = 2000
"""Enough for quadratic work (``MANY**2 / 2`` comparisons) to stand out from n log n."""


def test_statistics_of_many_resources_and_monitors_take_near_linear_work() -> None:
    names = [_Name(f"r{i}") for i in range(MANY)]
    events: list[ExecEvent] = [
        ActionSpawned(0.0, 1, "grab", None),
        ActionStarted(0.0, 1, "grab"),
        ResourceAcquired(0.0, 1, "grab", tuple(names), tuple(names), 0),
        *(MonitorFired(1.0, None, name, None, "v", "becomes=True", True, "none") for name in names),
    ]
    recording = Recording(RecordingHeader(t0=0.0), tuple(events), end=2.0)
    _Compared.times = 0
    summary = summarize(recording)
    page = render_timeline_html(recording)
    assert (len(summary.resources), summary.resources[0].held) == (MANY, 2.0)
    assert page.count('<rect class="hold"') == MANY
    assert page.count('<line class="firing"') == MANY
    assert _Compared.times < 60 * MANY  # sorting and hashing; was 4 * MANY**2 / 2 and more


def test_drawing_many_overlapping_actions_takes_near_linear_work() -> None:
    events: list[ExecEvent] = []
    for i in range(1, MANY + 1):
        time = _Time(i / 1000)
        events += [ActionSpawned(time, i, "walk", None), ActionStarted(time, i, "walk")]
    recording = Recording(RecordingHeader(t0=0.0), tuple(events), end=_Time(10.0))
    _Compared.times = 0
    page = render_timeline_html(recording)
    assert page.count('<rect class="action not_done"') == MANY
    assert f">walk (lane {MANY})</text>" in page  # none ends: each takes a lane of its own
    assert _Compared.times < 20 * MANY  # finding a lane: was MANY**2 / 2
