"""Benchmarks of the loop watchdog (DESIGN.md §10: a 100 ms block reported within 200 ms, 1 % CPU).

All with the default ``block_threshold`` (0.1 s), on a real-time loop unless
said otherwise; ``run()`` returns a flat dict:

- ``watchdog_report_delay_*_ms``: from the start of a block (an action that
  blocks the loop thread until the WARNING comes) to the WARNING record,
  over `BLOCKS` blocks started at random phases of the watchdog's looks;
- ``watchdog_blocks_of_*ms_reported_pct``: blocks of a fixed length
  (``time.sleep`` in an action), how many were reported;
- ``watchdog_idle_cpu_overhead_pct``: an idle robot's process CPU time per
  second, watchdog on minus off (interleaved runs, median), in % of a core;
- ``watchdog_busy_overhead_pct``: the process CPU time of a busy workload
  (actions doing short pure-Python steps, never blocking), on over off, minus
  1, in % (median of `BUSY_ROUNDS` interleaved pairs, which of the two runs
  first alternating); on this shared 2-core machine the pairs scatter by a
  few % either way, far more than the watchdog costs, so the goal is checked
  on ``watchdog_busy_cpu_pct``: the CPU time the watchdog itself spends over
  that workload's wall time, counted directly: the loop's beats (their
  callbacks, timed on the loop thread's CPU clock) plus the watchdog thread's
  own CPU time. ``watchdog_thread_cpu_busy_pct`` is the thread's part (Linux:
  it sleeps in the kernel while the loop turns), ``watchdog_beats_per_s``
  how often the loop beat meanwhile, ``watchdog_beat_cpu_us`` what one
  beat cost (the epoll wake-up that delivers it is not counted: a few µs),
  and ``watchdog_wakes_per_100_beats_busy`` how often the thread woke
  meanwhile, per 100 beats (the loop carries the watch: none on a quiet
  machine; a loaded one that keeps the loop thread from its beat wakes it);
- ``watchdog_lockstep_walk_ratio``: the lockstep simulated random walk's
  speed (simulated seconds per wall second), on over off (median of
  interleaved pairs): virtual time must not be slowed.
"""

from __future__ import annotations

import asyncio
import logging
import random
import statistics
import threading
import time
from unittest import mock

from pyrobots_aio import Robot, action
from pyrobots_aio._core._blockwatch import BlockWatch
from pyrobots_aio._core._timerfd import Timer
from pyrobots_aio.loops import run_lockstep
from pyrobots_aio.robot import _robot as robot_module
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk

BLOCKS = 30
FIXED = {120: 20, 150: 20, 200: 20}  # block length in ms -> blocks
IDLE_SECONDS = 2.0
ROUNDS = 5
BUSY_ROUNDS = 15
BUSY_STEPS = 100_000
WALK_SECONDS = 60.0


class _Warnings(logging.Handler):
    """Stamps each WARNING of the watchdog (``perf_counter``) and wakes a blocked loop."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.stamps: list[float] = []
        self.warned = threading.Event()

    def emit(self, record: logging.LogRecord) -> None:
        self.stamps.append(time.perf_counter())
        self.warned.set()


@action
async def _block_until_reported(robot: Robot, seen: _Warnings) -> float:
    start = time.perf_counter()
    seen.warned.wait(1.0)  # a real block, ended by the report (or after 1 s: missed)
    return start


@action
async def _block_for(robot: Robot, seconds: float) -> None:
    time.sleep(seconds)  # noqa: ASYNC251 (the block under test)


async def _delays(seen: _Warnings) -> dict[str, float]:
    rng = random.Random(1)
    delays = []
    async with Robot(actions=[_block_until_reported, _block_for]) as robot:
        for _ in range(BLOCKS):
            await asyncio.sleep(0.1 + rng.uniform(0, 0.05))  # any phase of its looks
            seen.warned.clear()
            start = await robot._block_until_reported(seen)
            delays.append(seen.stamps[-1] - start if seen.warned.is_set() else float("inf"))
        figures = {
            "watchdog_report_delay_median_ms": statistics.median(delays) * 1e3,
            "watchdog_report_delay_max_ms": max(delays) * 1e3,
        }
        for ms, count in FIXED.items():
            before = len(seen.stamps)
            for _ in range(count):
                await asyncio.sleep(0.1 + rng.uniform(0, 0.05))
                await robot._block_for(ms / 1e3)
            await asyncio.sleep(0.1)
            reported = len(seen.stamps) - before
            figures[f"watchdog_blocks_of_{ms}ms_reported_pct"] = 100 * reported / count
    return figures


async def _idle_cpu(threshold: float | None) -> float:
    async with Robot(block_threshold=threshold):
        await asyncio.sleep(0.1)
        cpu, wall = time.process_time(), time.perf_counter()
        await asyncio.sleep(IDLE_SECONDS)
        return (time.process_time() - cpu) / (time.perf_counter() - wall)


@action
async def _worker(robot: Robot, steps: int) -> None:
    total = 0
    for i in range(steps):
        for j in range(200):  # ~10 us of pure Python a step
            total += i ^ j
        await asyncio.sleep(0)


class _TimedBeats(BlockWatch):
    """A watchdog whose beats add up the loop thread's CPU time they take."""

    spent = 0.0

    def _beat(self, beat: Timer, deadline: Timer) -> None:
        cpu = time.thread_time()
        super()._beat(beat, deadline)
        _TimedBeats.spent += time.thread_time() - cpu


async def _busy(threshold: float | None) -> tuple[float, float, float, float, int, int]:
    """Process CPU s, wall s, the watchdog thread's and the beats' CPU s, the beats and wakes."""
    with mock.patch.object(robot_module, "BlockWatch", _TimedBeats):
        async with Robot(actions=[_worker], block_threshold=threshold) as robot:
            watch = robot._blockwatch
            thread = next((t for t in threading.enumerate() if "loop watchdog" in t.name), None)
            clock = None if thread is None else time.pthread_getcpuclockid(thread.ident or 0)
            own = 0.0 if clock is None else time.clock_gettime(clock)
            beats = 0 if watch is None else watch.beats
            wakes = 0 if watch is None else watch.wakes
            _TimedBeats.spent = 0.0
            cpu, wall = time.process_time(), time.perf_counter()
            await asyncio.gather(*(robot._worker(BUSY_STEPS // 20) for _ in range(20)))
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
            own = 0.0 if clock is None else time.clock_gettime(clock) - own
            beats = 0 if watch is None else watch.beats - beats
            wakes = 0 if watch is None else watch.wakes - wakes
            spent = _TimedBeats.spent
    return cpu, wall, own, spent, beats, wakes


async def _walk(threshold: float | None) -> float:
    robot = SimRobot(seed=1, block_threshold=threshold)
    wall = time.perf_counter()
    async with robot:
        report = await random_walk(robot, duration=WALK_SECONDS, seed=1)
    return report.sim_time / (time.perf_counter() - wall)


def _busy_pairs() -> dict[str, float]:
    busy, own_cpu, thread, beats, beat_cost, wakes = [], [], [], [], [], []
    for round_ in range(BUSY_ROUNDS):
        first, second = (0.1, None) if round_ % 2 == 0 else (None, 0.1)
        runs = {first: asyncio.run(_busy(first)), second: asyncio.run(_busy(second))}
        (cpu_on, wall_on, own, spent, beaten, woken), (cpu_off, *_) = runs[0.1], runs[None]
        busy.append((cpu_on / cpu_off - 1) * 100)
        own_cpu.append((own + spent) / wall_on * 100)
        thread.append(own / wall_on * 100)
        beats.append(beaten / wall_on)
        beat_cost.append(spent / max(beaten, 1) * 1e6)
        wakes.append(100 * woken / max(beaten, 1))
    return {
        "watchdog_busy_overhead_pct": statistics.median(busy),
        "watchdog_busy_cpu_pct": statistics.median(own_cpu),
        "watchdog_thread_cpu_busy_pct": statistics.median(thread),
        "watchdog_beats_per_s": statistics.median(beats),
        "watchdog_beat_cpu_us": statistics.median(beat_cost),
        "watchdog_wakes_per_100_beats_busy": statistics.median(wakes),
    }


def _overheads() -> dict[str, float]:
    idle, walk = [], []
    for _ in range(ROUNDS):
        on, off = asyncio.run(_idle_cpu(0.1)), asyncio.run(_idle_cpu(None))
        idle.append((on - off) * 100)
        walk.append(run_lockstep(_walk, 0.1) / run_lockstep(_walk, None))
    return {
        "watchdog_idle_cpu_overhead_pct": statistics.median(idle),
        **_busy_pairs(),
        "watchdog_lockstep_walk_ratio": statistics.median(walk),
    }


def run() -> dict[str, float]:
    """Measure the watchdog; return the figures."""
    seen = _Warnings()
    logger = logging.getLogger("pyrobots_aio.watchdog")
    logger.addHandler(seen)
    propagate, logger.propagate = logger.propagate, False  # keep the reports off the console
    try:
        figures = asyncio.run(_delays(seen))
    finally:
        logger.removeHandler(seen)
        logger.propagate = propagate
    figures.update(_overheads())
    return figures


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:44} {value:12.3f}")
