"""What recording costs (issue 7: at most 2x on action throughput; issue 14: at most 1.5x
on the lockstep random walk).

``run()`` measures, in this same run, with rounds alternating and each figure
keeping its best round:

- sequential start+finish of no-op actions on a plain robot, without a
  recorder and with a `JsonlRecorder` writing to a real file;
- the lockstep random walk of a `SimRobot` (`WALK_SECONDS` simulated), without
  a recorder, with a `JsonlRecorder` recording every sensor key and the pose at
  the control rate (50 Hz) and every executive event, and with a `McapRecorder`
  doing the same (informative);
- replaying (load, summary, page) two crafted recordings of `CROWD` items
  (issue 26): one event holding that many distinct resources, and that many
  overlapping actions. Both took quadratic time: 16.5 s and 4.9 s of CPU before
  (grouping by resource by scanning every hold for each resource; first-fit
  lanes by scanning every lane), 0.64 s and 0.59 s after.

Times are the thread's CPU time (``time.thread_time``), so that other
processes on a shared machine weigh less on the ratios.
"""

from __future__ import annotations

import asyncio
import json
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

from pyrobots_aio import Robot, action
from pyrobots_aio.loops import run_lockstep
from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    format_summary,
    load,
    render_timeline_html,
    summarize,
)
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio.recording import Recorder

N = 20_000
ROUNDS = 5
WALK_SECONDS = 120.0
WALK_ROUNDS = 5
CROWD = 20_000


@action
async def nop(robot: Robot) -> int:
    return 1


async def _actions(robot: Robot) -> float:
    async with robot:
        for _ in range(200):  # warm up
            await nop(robot)
        start = time.thread_time()
        for _ in range(N):
            await nop(robot)
        return time.thread_time() - start


def _bare() -> float:
    return asyncio.run(_actions(Robot()))


def _recorded(path: Path) -> float:
    robot = Robot()
    with JsonlRecorder(path).attach(robot):
        return asyncio.run(_actions(robot))


async def _walk(recorder: Recorder | None) -> float:
    robot = SimRobot(seed=1)
    if recorder is not None:
        recorder.attach(robot)
    try:
        start = time.thread_time()
        async with robot:
            await random_walk(robot, duration=WALK_SECONDS, seed=1)
        return time.thread_time() - start
    finally:
        if recorder is not None:
            recorder.close()


def _walks(tmp: Path) -> dict[str, float]:
    makers: dict[str, Callable[[], Recorder | None]] = {
        "bare": lambda: None,
        "jsonl": lambda: JsonlRecorder(tmp / "walk.jsonl"),
        "mcap": lambda: McapRecorder(tmp / "walk.mcap"),
    }
    best = dict.fromkeys(makers, float("inf"))
    for _ in range(WALK_ROUNDS):
        for name, make in makers.items():
            best[name] = min(best[name], run_lockstep(_walk, make()))
    recording = load(tmp / "walk.jsonl")
    return {
        "walk_recording_overhead_ratio": best["jsonl"] / best["bare"],
        "walk_mcap_overhead_ratio": best["mcap"] / best["bare"],
        "walk_realtime_factor_recorded": WALK_SECONDS / best["jsonl"],
        "walk_recorded_samples_per_sim_s": recording.state_samples / recording.duration,
        "walk_recorded_bytes_per_sim_s": (tmp / "walk.jsonl").stat().st_size / recording.duration,
    }


def _crowd_file(path: Path, records: list[dict[str, object]]) -> Path:
    header = {"format": "pyrobots_aio.recording", "version": 2, "t0": 0.0}
    lines = [header, *records, {"end": 30.0, "events": len(records)}]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def _replay_seconds(path: Path) -> float:
    start = time.thread_time()
    recording = load(path)
    format_summary(summarize(recording))
    render_timeline_html(recording)
    return time.thread_time() - start


def _crowds(tmp: Path) -> dict[str, float]:
    """Replay seconds of one event holding `CROWD` resources, and of `CROWD` overlapping actions."""

    def event(t: float, kind: str, ident: int, **data: object) -> dict[str, object]:
        return {"t": t, "action": ident, "kind": kind, "name": "a", "data": data}

    names = [f"r{i}" for i in range(CROWD)]
    held = [event(0.0, "action.spawned", 1, parent=None), event(0.0, "action.started", 1)]
    held.append(event(0.0, "resource.acquired", 1, resources=names, leaves=names, priority=0))
    crowd = [
        event(i / 1000, kind, i, parent=None)
        for i in range(1, CROWD + 1)
        for kind in ("action.spawned", "action.started")
    ]
    return {
        "replay_20k_resources_s": _replay_seconds(_crowd_file(tmp / "held.jsonl", held)),
        "replay_20k_overlapping_actions_s": _replay_seconds(
            _crowd_file(tmp / "crowd.jsonl", crowd)
        ),
    }


def run() -> dict[str, float]:
    bare, recorded = [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jsonl"
        for _ in range(ROUNDS):
            bare.append(_bare())
            recorded.append(_recorded(path))
        events = len(load(path).events)
        size = path.stat().st_size
        walks = _walks(Path(tmp))
        crowds = _crowds(Path(tmp))
    assert events == 3 * (N + 200), events
    actions = {
        "recording_throughput_ratio": min(recorded) / min(bare),
        "actions_per_s_recorded": N / min(recorded),
        "actions_per_s_unrecorded": N / min(bare),
        "recording_bytes_per_event": size / events,
    }
    return walks | crowds | actions


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:32} {value:12.3f}")
