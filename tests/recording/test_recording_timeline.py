"""The replay page's timeline: every action, hold, wait and firing; lanes; a self-contained page."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

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
