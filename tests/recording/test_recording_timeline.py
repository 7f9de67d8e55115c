"""The timeline page: self-contained, and shown by a real headless browser (Debian's chromium)."""

from __future__ import annotations

import os
import re
import shutil
import struct
import subprocess
import zlib
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio.recording import JsonlRecorder, MemoryRecorder, load, render_timeline_html

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from conftest import Played
    from pyrobots_aio.recording import Recorder, Recording

    Scenario = Callable[[Recorder], Awaitable[Played]]

CHROMIUM_HELP = (
    "the timeline test needs a headless browser: install Debian's chromium "
    "(apt-get update && apt-get install -y chromium) or set PYROBOTS_CHROMIUM to a "
    "chromium binary"
)
GREEN, ORANGE, RED = (0x43, 0xA0, 0x47), (0xFB, 0x8C, 0x00), (0xE5, 0x39, 0x35)


def _chromium() -> str:
    found = os.environ.get("PYROBOTS_CHROMIUM") or shutil.which("chromium")
    if not found:
        pytest.fail(CHROMIUM_HELP)
    return found


def _browse(page: Path, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    command = [
        _chromium(),
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        f"--user-data-dir={profile}",
        "--window-size=1400,900",
        *args,
        page.as_uri(),
    ]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=True)


def _png_pixels(data: bytes) -> tuple[int, int, list[tuple[int, int, int]]]:
    """Decode an 8-bit RGB or RGBA, non-interlaced PNG (what chromium writes)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, header = 8, b"", b""
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        header = body if kind == b"IHDR" else header
        idat += body if kind == b"IDAT" else b""
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", header)
    assert (depth, colour, interlace) in {(8, 2, 0), (8, 6, 0)}
    size = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * size
    previous, pixels = bytearray(stride), []
    for y in range(height):
        kind, line = (
            raw[y * (stride + 1)],
            bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)]),
        )
        for i in range(stride):
            left = line[i - size] if i >= size else 0
            up, corner = previous[i], previous[i - size] if i >= size else 0
            if kind == 1:
                line[i] = (line[i] + left) & 0xFF
            elif kind == 2:
                line[i] = (line[i] + up) & 0xFF
            elif kind == 3:
                line[i] = (line[i] + (left + up) // 2) & 0xFF
            elif kind == 4:
                p = left + up - corner
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                best = left if pa <= pb and pa <= pc else up if pb <= pc else corner
                line[i] = (line[i] + best) & 0xFF
        pixels += [tuple(line[i : i + 3]) for i in range(0, stride, size)]
        previous = line
    return width, height, pixels  # type: ignore[return-value]


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
    assert labels[:5] == [
        ("8", "patrol x1"),
        ("22", "drive x3"),
        ("8", "wave x2"),
        ("8", "reflex x1"),
        ("8", "oops x1"),
    ]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_page_is_self_contained(tmp_path: Path, record_scenario: Scenario) -> None:
    page = render_timeline_html(await _scenario(tmp_path, record_scenario))
    assert "<script" not in page
    assert "src=" not in page
    assert "href=" not in page
    assert "url(" not in page
    assert "@import" not in page
    assert set(re.findall(r"https?://[^\s\"']+", page)) == {"http://www.w3.org/2000/svg"}


def test_empty_and_partial_recordings_still_render() -> None:
    page = render_timeline_html(MemoryRecorder().recording())
    assert "the recording was not closed" in page
    assert _count(page, r'<rect class="action ') == 0


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_headless_browser_shows_the_actions(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    page = tmp_path / "timeline.html"
    page.write_text(render_timeline_html(await _scenario(tmp_path, record_scenario)))

    dom = _browse(page, tmp_path / "profile-dom", "--dump-dom").stdout
    assert _count(dom, r'<rect class="action ') == 9
    assert _count(dom, r'<rect class="hold"') == 6
    assert _count(dom, r'<svg class="(timeline|rates)"') == 2

    shot = tmp_path / "timeline.png"
    _browse(page, tmp_path / "profile-shot", f"--screenshot={shot}")
    width, height, pixels = _png_pixels(shot.read_bytes())
    assert (width, height) == (1400, 900)
    colours = {colour: pixels.count(colour) for colour in (GREEN, ORANGE, RED)}
    # far more than the 12x12 legend swatches: the bars themselves are drawn
    assert colours[GREEN] > 5000, colours
    assert colours[ORANGE] > 1000, colours
    assert colours[RED] > 300, colours
