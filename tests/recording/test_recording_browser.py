"""The replay page in a real headless browser (chromium), looked at as a person would.

Chromium lays the page out and runs its script; a probe script added to a copy
of the page measures what was drawn (the path's bounding box in the map
frame, element counts) and the screenshot is checked for the colours of the
bars, the dock, the path and the bump marks.

Without a browser on PATH these tests are skipped, with the reason; under CI
(``.ci/run`` installs chromium and sets ``PYROBOTS_BROWSER_REQUIRED=1``) a
missing browser fails them instead.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import struct
import subprocess
import zlib
from collections import Counter
from typing import TYPE_CHECKING, Any

import pytest
from devtools import FLAGS, Browser
from test_recording_pauses import SPELLS, _play

from pyrobots_aio.recording import JsonlRecorder, load, render_timeline_html
from pyrobots_aio.recording._analysis import analyse
from pyrobots_aio.recording._map import STEP_PX, marks
from pyrobots_aio.recording._plots import plotted
from pyrobots_aio.recording._script import MAX_ZOOM, WHEEL
from pyrobots_aio.recording._timeline import PAUSED_INK, PAUSED_PALE
from pyrobots_aio.sim import SimRobot, run
from pyrobots_aio.sim.random_walk import random_walk

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable
    from pathlib import Path

    from devtools import Page

    from conftest import Played
    from pyrobots_aio.recording import Recorder, Recording

    Scenario = Callable[[Recorder], Awaitable[Played]]

REQUIRED = "PYROBOTS_BROWSER_REQUIRED"
BROWSER_HELP = (
    "no headless browser: the page test needs chromium on PATH (Debian: apt-get install "
    "chromium) or PYROBOTS_CHROMIUM naming one"
)
GREEN, ORANGE, RED = (0x43, 0xA0, 0x47), (0xFB, 0x8C, 0x00), (0xE5, 0x39, 0x35)
DOCK, BUMP = (0x33, 0x33, 0x38), (0xD5, 0x00, 0x00)
PROBE = """<script>
function hover(map) {
  // Move the mouse over the first bump mark, then over the timeline at that mark's time.
  var mark = map.querySelector("path.mark.bump"), t = +mark.dataset.t;
  var timeline = document.querySelector("svg.timeline"), cursor = timeline.querySelector(".cursor");
  var at = mark.getBoundingClientRect(), here = map.querySelector(".here");
  map.dispatchEvent(new MouseEvent("mousemove", {
    clientX: at.left + at.width / 2, clientY: at.top + at.height / 2, bubbles: true
  }));
  var fromMap = {cursor: +cursor.getAttribute("x1"), shown: cursor.style.display !== "none"};
  here.setAttribute("cx", "-99");
  var point = timeline.createSVGPoint();
  point.x = +timeline.dataset.x0 + t / +timeline.dataset.duration * +timeline.dataset.w;
  point.y = 60;
  var screen = point.matrixTransform(timeline.getScreenCTM());
  timeline.dispatchEvent(new MouseEvent("mousemove", {
    clientX: screen.x, clientY: screen.y, bubbles: true
  }));
  var box = here.getBoundingClientRect();
  return {
    t: t, cursor: fromMap.cursor, shown: fromMap.shown, expected: point.x,
    here: [
      box.left + box.width / 2 - at.left - at.width / 2,
      box.top + box.height / 2 - at.top - at.height / 2
    ]
  };
}
window.addEventListener("load", function () {
  var map = document.querySelector("svg.map"), box = map.querySelector("g.trail").getBBox();
  var k = +map.dataset.scale, ox = +map.dataset.ox, oy = +map.dataset.oy;
  var count = function (selector) { return document.querySelectorAll(selector).length; };
  var sum = function (selector) {  // marks drawn once for each place, with their count
    return Array.prototype.reduce.call(document.querySelectorAll(selector), function (n, mark) {
      return n + +mark.dataset.count;
    }, 0);
  };
  var out = document.createElement("pre");
  out.id = "probe";
  out.textContent = JSON.stringify({
    x: [(box.x - ox) / k, (box.x + box.width - ox) / k],
    y: [(oy - box.y - box.height) / k, (oy - box.y) / k],
    trail: count("svg.map polyline.trail"), shapes: count("svg.map .shape"),
    dock: count("svg.map .shape.dock"), bumps: sum("svg.map path.mark.bump"),
    headings: count("svg.map path.heading"),
    marks: sum("svg.map path.mark"), plots: count("svg.timeline polyline.plot"),
    pulses: count("svg.timeline rect.plot.bool"), actions: count("svg.timeline rect.action"),
    hover: hover(map)
  });
  document.body.appendChild(out);
});
</script>"""


def _chromium() -> str:
    found = (
        os.environ.get("PYROBOTS_CHROMIUM")
        or shutil.which("chromium")
        or shutil.which("chromium-browser")
    )
    if not found:
        if os.environ.get(REQUIRED) == "1":
            pytest.fail(f"{BROWSER_HELP}; {REQUIRED}=1 (CI) requires it")
        pytest.skip(BROWSER_HELP)
    return found


def _browse(page: Path, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    command = [
        _chromium(),
        *FLAGS,
        f"--user-data-dir={profile}",
        "--window-size=1400,1000",
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


def _near(
    seen: Counter[tuple[int, int, int]], colour: tuple[int, int, int], within: int = 6
) -> int:
    """How many pixels are within ``within`` of ``colour`` on each channel."""
    return sum(
        count
        for pixel, count in seen.items()
        if all(abs(a - b) <= within for a, b in zip(pixel, colour, strict=True))
    )


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_headless_browser_shows_the_actions(
    tmp_path: Path, record_scenario: Scenario
) -> None:
    _chromium()
    path = tmp_path / "run.jsonl"
    await record_scenario(JsonlRecorder(path, state_keys=["bumper"]))
    page = tmp_path / "timeline.html"
    page.write_text(render_timeline_html(load(path)))

    dom = _browse(page, tmp_path / "profile-dom", "--dump-dom").stdout
    assert len(re.findall(r'<rect class="action ', dom)) == 9
    assert len(re.findall(r'<rect class="hold"', dom)) == 6
    assert len(re.findall(r'<svg class="(timeline|rates)"', dom)) == 2

    shot = tmp_path / "timeline.png"
    _browse(page, tmp_path / "profile-shot", f"--screenshot={shot}")
    width, height, pixels = _png_pixels(shot.read_bytes())
    assert (width, height) == (1400, 1000)
    colours = {colour: pixels.count(colour) for colour in (GREEN, ORANGE, RED)}
    # far more than the 12x12 legend swatches: the bars themselves are drawn
    assert colours[GREEN] > 5000, colours
    assert colours[ORANGE] > 1000, colours
    assert colours[RED] > 300, colours


def _rgb(colour: str) -> tuple[int, int, int]:
    r, g, b = (int(colour[i : i + 2], 16) for i in (1, 3, 5))
    return r, g, b


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_headless_browser_shows_the_paused_spells_hatched(tmp_path: Path) -> None:
    _chromium()
    path = tmp_path / "pauses.jsonl"
    await _play(JsonlRecorder(path))
    page = tmp_path / "pauses.html"
    page.write_text(render_timeline_html(load(path)))

    dom = _browse(page, tmp_path / "profile-dom", "--dump-dom").stdout
    assert len(re.findall(r'<rect class="paused"', dom)) == 8
    shot = tmp_path / "pauses.png"
    _browse(page, tmp_path / "profile-shot", f"--screenshot={shot}")
    seen = Counter(_png_pixels(shot.read_bytes())[2])
    # 8 spells, 1716 px (of 936 px for 6 s) by 13 px: stripes of ink on the pale ground
    spells = sum(len(s) for s in SPELLS.values())
    assert spells == 8
    ink, pale = _near(seen, _rgb(PAUSED_INK)), _near(seen, _rgb(PAUSED_PALE))
    assert ink > 2000, (ink, pale)
    assert pale > 6000, (ink, pale)


async def _walk(path: Path) -> None:
    robot = SimRobot(seed=1)
    with JsonlRecorder(path).attach(robot):
        async with robot:
            await random_walk(robot, duration=60, seed=1)


def _expected(recording: Recording) -> dict[str, int]:
    found = analyse(recording)
    numbers = [s for s in plotted(recording) if not all(isinstance(v, bool) for v in s.values)]
    kinds = [m.kind for m in marks(recording, found)]
    return {"bumps": kinds.count("bump"), "marks": len(kinds), "plots": len(numbers)}


def test_the_map_path_and_plots_are_drawn_where_the_robot_went(tmp_path: Path) -> None:
    _chromium()
    path = tmp_path / "walk.jsonl"
    run(_walk, path)  # lockstep virtual time
    recording = load(path)
    html = render_timeline_html(recording)
    page = tmp_path / "walk.html"
    page.write_text(html.replace("</body>", PROBE + "</body>"))

    dom = _browse(page, tmp_path / "profile-dom", "--dump-dom").stdout
    found = re.search(r'<pre id="probe">([^<]*)</pre>', dom)
    assert found is not None, dom[-2000:]
    probe = json.loads(found.group(1))
    expected = _expected(recording)
    assert expected["bumps"] >= 1  # this walk bumps into something
    assert (probe["bumps"], probe["marks"], probe["plots"]) == (
        expected["bumps"],
        expected["marks"],
        expected["plots"],
    )
    assert probe["pulses"] == expected["bumps"]  # the bumper plot: one pulse per bump
    assert probe["shapes"] == len(recording.header.floor_plan) == 8
    assert probe["dock"] == 1
    assert 10 <= probe["trail"] <= 240
    assert 10 <= probe["headings"] <= 60
    assert probe["actions"] == len(analyse(recording).spans)
    # The drawn path covers the recorded poses, to within its pixel step.
    poses = recording.poses
    scale = float(re.search(r'data-scale="([\d.]+)"', html).group(1))  # type: ignore[union-attr]
    slack = (STEP_PX + 0.5) / scale
    assert probe["x"][0] == pytest.approx(min(poses.x), abs=slack)
    assert probe["x"][1] == pytest.approx(max(poses.x), abs=slack)
    assert probe["y"][0] == pytest.approx(min(poses.y), abs=slack)
    assert probe["y"][1] == pytest.approx(max(poses.y), abs=slack)

    # Hover links both ways: the mark's place on the map shows its time on the timeline,
    # and its time on the timeline puts the map's "here" circle on the mark.
    hover = probe["hover"]
    assert hover["shown"]
    assert hover["cursor"] == pytest.approx(hover["expected"], abs=2.0)  # pixels of the timeline
    assert abs(hover["here"][0]) < 3
    assert abs(hover["here"][1]) < 3

    shot = tmp_path / "walk.png"
    _browse(page, tmp_path / "profile-shot", f"--screenshot={shot}")
    seen = Counter(_png_pixels(shot.read_bytes())[2])
    assert _near(seen, DOCK) > 200  # the dock, from the model's colour
    assert _near(seen, BUMP, within=20) > 20  # the bump marks
    trail = {tuple(int(c[i : i + 2], 16) for i in (1, 3, 5)) for c in re.findall(
        r'class="trail" points="[^"]*" style="stroke:(#[0-9a-f]{6})"', html
    )}  # fmt: skip
    assert sum(_near(seen, colour, within=2) for colour in trail) > 1000  # the path itself


def _action(id_: int, begin: float, end: float) -> list[dict[str, Any]]:
    def event(t: float, kind: str, **data: object) -> dict[str, Any]:
        return {"t": t, "action": id_, "kind": kind, "name": "drive", "data": data}

    return [
        event(begin, "action.spawned", parent=None),
        event(begin, "action.started"),
        event(end, "action.finished", outcome="succeeded"),
    ]


def _known(path: Path) -> None:
    """Ten seconds whose values step on each whole second ``i``; bumps at 3 and 7, a cliff at 5.

    drive#1 runs from 1 to 1.2 s, too short for its label, and drive#2 at once after it.
    """
    header = {"format": "pyrobots_aio.recording", "version": 1, "t0": 0.0}
    header["floor_plan"] = [{"name": "wall", "shape": "box", "x": 0.5, "y": 1, "half": [1, 0.05]}]
    samples = [
        {
            "t": float(i),
            "state": {
                "v": i / 10,
                "w": -i / 100,
                "ir_front": round(0.4 - i / 100, 2),
                "bumper": i in {3, 7},
                "cliff_front_left": i == 5,
                "battery": round(1 - i / 100, 2),
                "encoder_left": i * 1.5,
            },
            "pose": [i / 10, 0.0, i / 10],
        }
        for i in range(10)
    ]
    records = sorted(
        [*samples, *_action(1, 1.0, 1.2), *_action(2, 1.25, 3.0)], key=lambda r: r["t"]
    )
    lines = [header, *records, {"end": 10.0, "events": len(records)}]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))


SHOWN_AT_3_5 = {
    "v": "v 0.3 m/s",
    "w": "w -0.03 rad/s",
    "ir_front": "ir_front 0.37 m",
    "bumper": "bumper true",
    "cliff_front_left": "cliff_front_left false",
    "battery": "battery 0.97",
    "encoder_left": "encoder_left 4.5 rad",
}
"""The readout at 3.5 s of `_known`: each row's value held since 3 s."""
GEOMETRY = """(function (t) {
  // The plot area on screen, and where time t is on the v row (CSS pixels of the viewport).
  var svg = document.querySelector("svg.timeline"), view = svg.dataset.view.split(" ").map(Number);
  var row = document.querySelector("svg.timeline text.label[data-key='v']").getBBox();
  var ctm = svg.getScreenCTM(), x0 = +svg.dataset.x0, w = +svg.dataset.w;
  var x = x0 + (t - view[0]) / (view[1] - view[0]) * w;
  return {left: ctm.e + x0 * ctm.a, width: w * ctm.a, x: ctm.e + x * ctm.a,
          y: ctm.f + (row.y + 20) * ctm.d, view: view};
})"""
READOUT = """(function () {
  var spans = document.querySelectorAll(".readout span"), values = {};
  Array.prototype.forEach.call(spans, function (s) {
    if (s.dataset.key) { values[s.dataset.key] = s.textContent; }
  });
  return {hidden: document.querySelector(".readout").hidden,
          stamp: spans.length ? spans[0].textContent : "", values: values,
          cursor: document.querySelector("svg.timeline .cursor-time").textContent};
})()"""
LABEL = """Array.prototype.filter.call(
  document.querySelectorAll("svg.timeline text.in"),
  function (t) { return t.textContent === "drive#1"; }
)[0].getBoundingClientRect().width"""
"""How wide drive#1's label is drawn (0: hidden)."""
TICKS = """Array.prototype.map.call(
  document.querySelectorAll("svg.%s g.axis.time text"), function (t) { return t.textContent; }
).slice(1)"""


def _geometry(page: Page, t: float) -> dict[str, Any]:
    found: dict[str, Any] = page.evaluate(f"{GEOMETRY}({t})")
    return found


def _readout(page: Page) -> dict[str, Any]:
    shown: dict[str, Any] = page.evaluate(READOUT)
    return shown


def _seconds(stamp: str) -> float:
    found = re.fullmatch(r"t (-?[\d.]+) s", stamp)
    assert found is not None, stamp
    return float(found.group(1))


def test_the_page_zooms_pans_and_reads_values_at_the_cursor(tmp_path: Path) -> None:
    chromium = _chromium()
    path, html = tmp_path / "known.jsonl", tmp_path / "known.html"
    _known(path)
    html.write_text(render_timeline_html(load(path)))
    with Browser(chromium, tmp_path / "profile") as browser:
        page = browser.open(html.as_uri(), 1400, 3000)  # tall: every row in sight
        assert _readout(page)["hidden"]
        assert page.evaluate(TICKS % "timeline") == [str(i) for i in range(11)]
        assert page.evaluate(LABEL) == 0  # drive#1's bar is 19 px, its label needs 47 px

        # The cursor: each row's value at that moment, on every figure and on the map.
        at = _geometry(page, 3.5)
        pixel = 10.0 / at["width"]  # seconds per pixel, unzoomed
        page.mouse("mouseMoved", round(at["x"]), round(at["y"]))
        shown = _readout(page)
        assert not shown["hidden"]
        assert _seconds(shown["stamp"]) == pytest.approx(3.5, abs=pixel)
        assert shown["values"] == SHOWN_AT_3_5
        assert shown["cursor"] == f"{_seconds(shown['stamp']):.2f} s"
        heading = page.evaluate(
            'document.querySelector("svg.map .here-heading").getAttribute("transform")'
        )
        assert re.fullmatch(
            r"translate\([\d.]+,[\d.]+\) rotate\(-17\.18873\d*\)", heading
        )  # 0.3 rad

        # Five wheel notches up over 5 s: e^-1 of the time shown, 5 s kept under the mouse.
        at = _geometry(page, 5.0)
        x, y = round(at["x"]), round(at["y"])
        under = at["view"][0] + (x - at["left"]) / at["width"] * 10.0
        for _ in range(5):
            page.mouse("mouseWheel", x, y, deltaX=0, deltaY=-100)
        a, b = _geometry(page, 0.0)["view"]
        assert b - a == pytest.approx(10.0 * math.exp(-500 * WHEEL))
        assert a + (x - at["left"]) / at["width"] * (b - a) == pytest.approx(under)
        assert page.evaluate('document.querySelector("svg.rates").dataset.view') == (
            page.evaluate('document.querySelector("svg.timeline").dataset.view')
        )
        ticks = ["3.5", "4.0", "4.5", "5.0", "5.5", "6.0", "6.5"]  # round half seconds
        assert page.evaluate(TICKS % "timeline") == page.evaluate(TICKS % "rates") == ticks
        pulse = page.evaluate(
            'document.querySelector("svg.timeline rect.plot.bool").getBoundingClientRect().width'
        )
        assert pulse == pytest.approx(at["width"] / (b - a), abs=1.0)  # the bump at 3 s, 1 s long
        assert 30 < page.evaluate(LABEL) < 47  # 2.7 times wider, the bar holds its label

        # The readout, zoomed: the cursor is finer.
        at = _geometry(page, 4.25)
        page.mouse("mouseMoved", round(at["x"]), round(at["y"]))
        shown = _readout(page)
        assert _seconds(shown["stamp"]) == pytest.approx(4.25, abs=(b - a) / at["width"])
        assert (shown["values"]["v"], shown["values"]["bumper"]) == ("v 0.4 m/s", "bumper false")

        # A drag pans: 117 pixels to the right shows earlier times.
        page.mouse("mousePressed", x, y, button="left", buttons=1, clickCount=1)
        page.mouse("mouseMoved", x + 117, y, button="left", buttons=1)
        page.mouse("mouseReleased", x + 117, y, button="left", clickCount=1)
        panned = _geometry(page, 0.0)["view"]
        assert panned[0] == pytest.approx(a - 117 / at["width"] * (b - a))
        assert panned[1] - panned[0] == pytest.approx(b - a)

        # Over the labels the wheel leaves the time axis alone; at most MAX_ZOOM times.
        page.mouse("mouseWheel", round(at["left"]) - 100, y, deltaX=0, deltaY=-100)
        assert _geometry(page, 0.0)["view"] == panned
        for _ in range(30):
            page.mouse("mouseWheel", x, y, deltaX=0, deltaY=-100)
        a, b = _geometry(page, 0.0)["view"]
        assert b - a == pytest.approx(10.0 / MAX_ZOOM)

        # The button shows the whole run again.
        button = page.evaluate(
            '(function () { var r = document.querySelector(".reset-zoom").getBoundingClientRect();'
            " return [r.left + r.width / 2, r.top + r.height / 2]; })()"
        )
        page.mouse("mousePressed", *button, button="left", buttons=1, clickCount=1)
        page.mouse("mouseReleased", *button, button="left", clickCount=1)
        assert _geometry(page, 0.0)["view"] == [0, 10]
        assert page.evaluate(TICKS % "timeline") == [str(i) for i in range(11)]
        assert page.errors() == []
