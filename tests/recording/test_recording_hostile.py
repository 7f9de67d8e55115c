"""Untrusted recordings (issue 16): escaped everywhere on the page, safe and bounded to read.

The crafted files are written in the version 1 format (state samples as
``state.sample`` events), which this library still reads, so that the same
tests run against the code before the fixes and fail there.
"""

from __future__ import annotations

import html.parser
import json
import re
import tracemalloc
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import CorruptRecordingError
from pyrobots_aio.recording import format_summary, load, render_timeline_html, summarize

if TYPE_CHECKING:
    from pathlib import Path

HOSTILE = "x\"><script>alert(1)</script><img src=x onerror=alert(2)>'&"
"""Breaks out of an attribute (either quote), then of the text: a script and a handler."""
TAGS = {
    "html", "head", "meta", "title", "style", "body", "h1", "h2", "p", "span", "i", "svg",
    "g", "text", "rect", "line", "path", "polyline", "polygon", "circle", "script", "defs",
    "pattern",
}  # fmt: skip
CLASS = re.compile(r"^[a-z_][a-z0-9_ -]*$")


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
