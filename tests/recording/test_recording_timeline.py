"""The replay page's timeline: every action, hold, wait and firing; lanes; a self-contained page."""

from __future__ import annotations

import json
import math
import re
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio.recording import JsonlRecorder, MemoryRecorder, load, render_timeline_html
from pyrobots_aio.recording._timeline import _SCRIPT

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from conftest import Played
    from pyrobots_aio.recording import Recorder, Recording

    Scenario = Callable[[Recorder], Awaitable[Played]]


async def _scenario(tmp_path: Path, record_scenario: Scenario) -> Recording:
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    return load(path)


def _count(page: str, pattern: str) -> int:
    return len(re.findall(pattern, page))


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_page_draws_every_action_hold_wait_and_firing(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    page = render_timeline_html(await _scenario(tmp_path, record_scenario), title="scenario")
    assert page.startswith("<!DOCTYPE html>")
    assert _count(page, r'<rect class="action ') == 9
    assert _count(page, r'<rect class="action succeeded"') == 5
    assert _count(page, r'<rect class="action cancelled"') == 2
    assert _count(page, r'<rect class="action failed"') == 1
    assert _count(page, r'<rect class="action skipped"') == 1
    assert _count(page, r'<rect class="hold"') == 6
    assert _count(page, r'<rect class="wait"') == 2
    assert _count(page, r'<line class="firing"') == 1
    assert _count(page, r'<path class="preempt"') == 1
    assert _count(page, r'<rect class="state-on"') == 1
    assert _count(page, r'<rect class="rate-actions"') == 6  # 1-second buckets over 5.5 s
    tooltip = (
        "<title>drive#5: cancelled\n2.000 -&gt; 3.000 s (1.000 s)\nparent: patrol#1\n"
        "cancel requested at 3.000 s by reflex#6\n"
        "reason: preempted by reflex#6 (priority 5) for &#x27;wheels&#x27;</title>"
    )
    assert tooltip in page
    # rows: each action name under its parent's row, indented by depth
    labels = re.findall(r'<text class="label" x="(\d+)" y="[\d.]+">([^<]+)</text>', page)
    assert labels[:6] == [
        ("8", "patrol x1"),
        ("22", "drive x3"),
        ("8", "wave x2"),
        ("22", "wave (lane 2)"),  # every lane has its label
        ("8", "reflex x1"),
        ("8", "oops x1"),
    ]
    assert ("22", "wheels (lane 2)") not in labels  # no nested hold in this scenario
    assert _count(page, r'<rect class="plot bool"') == 1  # the bumper, plotted too


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_page_is_self_contained(tmp_path: Path, record_scenario: Scenario) -> None:
    page = render_timeline_html(await _scenario(tmp_path, record_scenario))
    assert page.count("<script") == 1  # the hover script, static text
    assert f"<script>{_SCRIPT}</script>" in page
    assert "src=" not in page
    assert "href=" not in page
    assert re.findall(r"url\(([^)]*)\)", page) == ["#paused-hatch"]  # the page's own pattern
    assert page.count('<pattern id="paused-hatch"') == 1
    assert "@import" not in page
    assert set(re.findall(r"https?://[^\s\"']+", page)) == {"http://www.w3.org/2000/svg"}


def test_empty_and_partial_recordings_still_render() -> None:
    page = render_timeline_html(MemoryRecorder().recording())
    assert "the recording was not closed" in page
    assert _count(page, r'<rect class="action ') == 0


def _samples(
    path: Path, samples: list[dict[str, Any]], end: float, plan: list[dict[str, Any]] | None = None
) -> Recording:
    header = {"format": "pyrobots_aio.recording", "version": 1, "t0": 0.0, "floor_plan": plan or []}
    lines = [header, *samples, {"end": end, "events": len(samples)}]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return load(path)


def test_axes_run_between_round_numbers(tmp_path: Path) -> None:
    samples = [
        {"t": 0.0, "state": {"v": 0.0, "w": 0.0}},
        {"t": 0.001, "state": {"v": 0.213, "w": 0.000231}},  # the w axis read 0.000231
    ]
    page = render_timeline_html(_samples(tmp_path / "small.jsonl", samples, end=0.0023))
    plots = re.findall(r'<text class="tick" [^>]*>([^<]*)</text>', page)
    assert plots == ["0.3", "0", "0.0003", "0"]  # v: top, bottom; w: top, bottom
    axis = re.search(r'<g class="axis time"[^>]*>(.*?)</g>', page)
    assert axis is not None
    seconds = re.findall(r'text-anchor="middle">([^<]*)</text>', axis.group(1))
    assert seconds == ["0", *(f"{i * 0.0002:.4f}" for i in range(1, 12))]


def test_battery_cliff_and_encoder_rows_are_drawn_when_recorded(tmp_path: Path) -> None:
    state: dict[str, object] = {"v": 0.1, "bumper": False, "ir_left": 0.4}
    more = {"battery": 0.9, "encoder_right": 2.0, "encoder_left": 1.0, "cliff_side": False}
    plain = _samples(tmp_path / "plain.jsonl", [{"t": 0.0, "state": state}], end=1.0)
    full = _samples(tmp_path / "full.jsonl", [{"t": 0.0, "state": state | more}], end=1.0)
    row = r'<text class="label" x="22" y="[\d.]+" data-key="(\w+)" data-unit="([\w/]*)"'
    assert re.findall(row, render_timeline_html(plain)) == [
        ("v", "m/s"),
        ("ir_left", "m"),
        ("bumper", ""),
    ]
    assert re.findall(row, render_timeline_html(full)) == [
        ("v", "m/s"),
        ("ir_left", "m"),
        ("bumper", ""),
        ("cliff_side", ""),
        ("battery", ""),
        ("encoder_left", "rad"),
        ("encoder_right", "rad"),
    ]


def _bump(t: float, x: float) -> list[dict[str, Any]]:
    return [
        {"t": t, "state": {"bumper": True}, "pose": [x, 0.0, 0.0]},
        {"t": t + 0.1, "state": {"bumper": False}, "pose": [x, 0.0, 0.0]},
    ]


def test_bumps_in_one_place_are_drawn_once_with_their_count(tmp_path: Path) -> None:
    corner = [sample for i in range(20) for sample in _bump(i, 1.0)]  # 20 times at x = 1 m
    run = [{"t": 0.0, "state": {"bumper": False}, "pose": [0.0, 0.0, 0.0]}, *corner]
    page = render_timeline_html(_samples(tmp_path / "bumps.jsonl", [*run, *_bump(25, 3.0)], 30))
    counts = re.findall(r'<path class="mark bump" [^>]* data-count="(\d+)"><title>([^<]*)', page)
    assert [(count, title.splitlines()[:2]) for count, title in counts] == [
        ("20", ["20 times here:", "bump (bumper) at 0.000 s"]),
        ("1", ["bump (bumper) at 25.000 s"]),
    ]
    assert counts[0][1].splitlines()[-1] == "and 12 more"  # 8 moments listed
    assert re.findall(r'<text class="count"[^>]*>(\d+)</text>', page) == ["20"]
    assert "bump (21)</span>" in page  # the legend counts them all


def test_the_heading_is_drawn_along_the_path(tmp_path: Path) -> None:
    north = [{"t": i / 10, "pose": [i / 10, 0.0, math.pi / 2], "state": {}} for i in range(101)]
    page = render_timeline_html(_samples(tmp_path / "north.jsonl", north, end=10.1))
    # 10 m drawn over 560 px, an arrow after each 60 px: one for each 11 poses of 5.6 px
    turns = re.findall(
        r'<path class="heading" transform="translate\([\d.,]+\) rotate\((-?\d+)\)"', page
    )
    assert turns == ["-90"] * 9
    assert '<path class="here-heading" transform="translate(-99,-99)"' in page
    track = re.search(r'data-track="([^"]*)"', page)
    assert track is not None
    assert track.group(1).split(";")[1] == "0.100,0.1000,0.0000,1.571"  # t, x, y, yaw
