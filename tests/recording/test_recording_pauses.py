"""Pauses in recordings (issue 13): each action's paused spells, on the page and in the summary.

A plain ``Robot()`` in virtual time, recorded to JSON Lines and MCAP at once:

t=0     top#1 starts kid#4 (a ticker); careful#2 and idle#3 (a ticker) start.
t=1     top#1 is paused ("hold still"): kid#4 freezes with it.
t=2     careful#2 is paused ("operator").
t=3     top#1 resumes (kid#4 with it); at 3.5 it is paused again ("again"), at 4.5 resumed.
t=4     careful#2 is cancelled ("give up"): that thaws it at once; its cleanup runs 1 s.
t=5     idle#3 is paused ("forever"); selfish#5 starts, pauses itself ("wait for the
        operator") and starts ticker#6, which starts frozen.
t=6     the recording stops, with idle#3, selfish#5 and ticker#6 still paused.
"""

from __future__ import annotations

import re
from dataclasses import astuple
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import ActionCancelled, Robot, action
from pyrobots_aio.actions import current_action
from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    MemoryRecorder,
    format_summary,
    load,
    render_timeline_html,
    summarize,
)
from pyrobots_aio.recording._analysis import STILL_PAUSED, analyse
from pyrobots_aio.recording._svg import LABEL_W, PLOT_W

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from pyrobots_aio.recording import Recorder, Recording

pytestmark = [pytest.mark.virtual_time, pytest.mark.asyncio]


@action
async def ticker(robot: Robot) -> None:
    while True:
        await robot.sleep(1.0)


@action
async def top(robot: Robot) -> None:
    ticker(robot)
    await robot.sleep(3600)


@action
async def careful(robot: Robot) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(1.0)  # the cleanup runs, unfrozen
        raise


@action
async def selfish(robot: Robot) -> None:
    me = current_action.get()
    assert me is not None
    me.pause("wait for the operator")
    ticker(robot)  # started by a frozen action: it starts frozen
    await robot.sleep(3600)


async def _play(*recorders: Recorder) -> None:
    """Play the scenario of the module notes; the recorders stop at t=6, before shutdown."""
    robot = Robot()
    for recorder in recorders:
        recorder.attach(robot)
    try:
        async with robot:
            first, cautious, idle = top(robot), careful(robot), ticker(robot)
            plan: list[tuple[float, Callable[..., object], tuple[object, ...]]] = [
                (1.0, first.pause, ("hold still",)),
                (2.0, cautious.pause, ("operator",)),
                (3.0, first.resume, ()),
                (3.5, first.pause, ("again",)),
                (4.0, cautious.cancel, ("give up",)),
                (4.5, first.resume, ()),
                (5.0, idle.pause, ("forever",)),
                (5.0, selfish, (robot,)),
            ]
            for at, call, args in plan:
                await robot.sleep(at - robot.time())
                call(*args)
            await robot.sleep(1)
            for recorder in recorders:
                recorder.close()  # the recording ends with three actions still paused
    finally:
        for recorder in recorders:
            recorder.close()


async def _recorded(tmp_path: Path) -> tuple[Recording, Recording]:
    jsonl, mcap = tmp_path / "pauses.jsonl", tmp_path / "pauses.mcap"
    await _play(JsonlRecorder(jsonl), McapRecorder(mcap))
    return load(jsonl), load(mcap)


SPELLS = {
    "top#1": [
        (1.0, 3.0, "resumed", "hold still", None, 1),
        (3.5, 4.5, "resumed", "again", None, 1),
    ],
    "careful#2": [(2.0, 4.0, "cancelled", "operator", None, 2)],
    "idle#3": [(5.0, None, STILL_PAUSED, "forever", None, 3)],
    "ticker#4": [
        (1.0, 3.0, "resumed", "hold still", None, 1),
        (3.5, 4.5, "resumed", "again", None, 1),
    ],
    "selfish#5": [(5.0, None, STILL_PAUSED, "wait for the operator", 5, 5)],
    "ticker#6": [(5.0, None, STILL_PAUSED, "wait for the operator", 5, 5)],
}
"""Each action's spells: start, end, how it ended, reason, who paused, whose pause froze it."""


def _spells(recording: Recording) -> dict[str, list[tuple[object, ...]]]:
    found = analyse(recording)
    named = {"top#1", "careful#2", "selfish#5", "ticker#4", "ticker#6"}
    spells = {}
    for span in found.spans.values():
        label = f"{span.name}#{span.id}"
        label = label if label in named else f"idle#{span.id}"
        spells[label] = [(p.start, p.end, p.ended, p.reason, p.by, p.root) for p in span.pauses]
    return spells


async def test_the_analysis_finds_each_spell_and_how_it_ended(tmp_path: Path) -> None:
    jsonl, mcap = await _recorded(tmp_path)
    assert (jsonl.start, jsonl.stop, jsonl.complete) == (0.0, 6.0, True)
    for recording in (jsonl, mcap):
        assert _spells(recording) == SPELLS
    found = analyse(jsonl)
    assert found.spans[2].outcome == "cancelled"
    assert (found.spans[2].cancelled_at, found.spans[2].finished) == (4.0, 5.0)
    assert found.spans[3].paused is not None  # still paused at the end
    assert found.spans[1].paused is None


async def test_the_page_hatches_each_spell_over_its_bar(tmp_path: Path) -> None:
    jsonl, mcap = await _recorded(tmp_path)
    page = render_timeline_html(jsonl, title="pauses")
    assert render_timeline_html(mcap, title="pauses").replace(".mcap", ".jsonl") == page
    bars = re.findall(
        r'<rect class="paused" x="([\d.]+)" y="[\d.]+" width="([\d.]+)" height="[\d.]+">'
        r"<title>([^<]*)</title>",
        page,
    )
    assert len(bars) == sum(len(spells) for spells in SPELLS.values()) == 8

    def x(t: float) -> float:  # the page's scale: 6 s over the plot's width
        return LABEL_W + t / 6.0 * PLOT_W

    extents = sorted((float(a), float(w)) for a, w, _ in bars)
    expected = sorted(
        (round(x(start), 1), round(x(6.0 if end is None else end) - x(start), 1))
        for spells in SPELLS.values()
        for start, end, *_ in spells
    )
    assert extents == expected
    titles = [title for _, _, title in bars]
    assert (
        "careful#2: paused\n2.000 -&gt; 4.000 s (2.000 s), cancelled\nreason: operator"
    ) in titles
    assert (
        "ticker#6: paused\n5.000 -&gt; 6.000 s (1.000 s), still paused\n"
        "frozen with selfish#5\npaused by selfish#5\nreason: wait for the operator"
    ) in titles
    assert "ticker#4: paused\n3.500 -&gt; 4.500 s (1.000 s), resumed\nfrozen with top#1" in (
        "\n".join(titles)
    )
    # the action's own tooltip adds them up; its bar is drawn whole, under the hatching
    assert "top#1: not done\n0.000 -&gt; 6.000 s (6.000 s)\nparent: root scope\n" in page
    assert page.count("paused 2 times, 3.000 s in total</title>") == 2  # top#1, ticker#4
    assert "paused once, 2.000 s in total</title>" in page  # careful#2
    assert page.count('<rect class="action ') == 6
    assert page.count("<pattern id=") == 1
    assert '<span><i style="background:repeating-linear-gradient(' in page  # the legend
    assert ">paused</span>" in page
    assert "paused 5 times, 7.000 s in total (6 actions frozen) &middot;" in page


async def test_the_summary_counts_pauses_only_when_there_were_any(tmp_path: Path) -> None:
    jsonl, mcap = await _recorded(tmp_path)
    summary = summarize(jsonl)
    assert summarize(mcap) == summary
    # top#1 twice (2 s + 1 s), careful#2 (2 s), idle#3 (1 s), selfish#5 (1 s): the
    # children frozen with them are not counted again, but they were frozen.
    assert (summary.pauses, summary.paused_time, summary.frozen_actions) == (5, 7.0, 6)
    report = format_summary(summary).splitlines()
    assert report[5] == "  paused             5 times, 7.000 s in total (6 actions frozen)"
    assert report[4].startswith("  peak concurrency")

    robot = Robot()
    with MemoryRecorder().attach(robot) as memory:
        async with robot:
            await robot.sleep(1)
            handle = ticker(robot)
            await robot.sleep(1.5)
            handle.pause()
            await robot.sleep(0.25)
            handle.resume()
    once = summarize(memory.recording())
    assert (once.pauses, once.paused_time, once.frozen_actions) == (1, 0.25, 1)
    assert "  paused             once, 0.250 s in total (1 action frozen)" in format_summary(once)

    plain = Robot()
    with MemoryRecorder().attach(plain) as memory:
        async with plain:
            ticker(plain)
            await plain.sleep(2)
    unpaused = summarize(memory.recording())
    assert (unpaused.pauses, unpaused.paused_time, unpaused.frozen_actions) == (0, 0.0, 0)
    assert "paused" not in format_summary(unpaused)
    facts = re.search(r'<p class="facts">[^<]*</p>', render_timeline_html(memory.recording()))
    assert facts is not None
    assert "paused" not in facts.group()


async def test_pause_all_counts_one_pause_per_root(tmp_path: Path) -> None:
    path = tmp_path / "all.jsonl"
    robot = Robot()
    with JsonlRecorder(path).attach(robot):
        async with robot:
            top(robot), ticker(robot)
            await robot.sleep(0.5)
            robot.pause_all("tea break")
            await robot.sleep(2)
            robot.resume_all()
            await robot.sleep(0.5)
    recording = load(path)
    spells = {
        span.id: [astuple(p)[:3] for p in span.pauses] for span in analyse(recording).spans.values()
    }
    assert spells == {i: [(0.5, "tea break", None)] for i in (1, 2, 3)}
    assert [(p.end, p.ended) for s in analyse(recording).spans.values() for p in s.pauses] == [
        (2.5, "resumed")
    ] * 3
    summary = summarize(recording)
    assert (summary.pauses, summary.paused_time, summary.frozen_actions) == (2, 4.0, 3)
