"""What recording costs the executive (issue 7: at most 2x on action start+finish throughput).

``run()`` measures sequential start+finish of no-op actions on a plain robot,
without a recorder and with a `JsonlRecorder` writing to a real file, in this
same run; rounds alternate and each figure keeps its best round. Times are the
thread's CPU time (``time.thread_time``), so that other processes on a shared
machine weigh less on the ratio.
"""

from __future__ import annotations

import asyncio
import tempfile
import time
from pathlib import Path

from pyrobots_aio import Robot, action
from pyrobots_aio.recording import JsonlRecorder, load

N = 20_000
ROUNDS = 5


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


def run() -> dict[str, float]:
    bare, recorded = [], []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.jsonl"
        for _ in range(ROUNDS):
            bare.append(_bare())
            recorded.append(_recorded(path))
        events = len(load(path).events)
        size = path.stat().st_size
    assert events == 3 * (N + 200), events
    return {
        "recording_throughput_ratio": min(recorded) / min(bare),
        "actions_per_s_recorded": N / min(recorded),
        "actions_per_s_unrecorded": N / min(bare),
        "recording_bytes_per_event": size / events,
    }


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:32} {value:12.3f}")
