"""Benchmarks of the action executive against bare asyncio tasks (DESIGN.md §10).

``run()`` returns the figures in a flat dict; every ratio compares two things
measured in this same run, on this same machine.
"""

from __future__ import annotations

import asyncio
import gc
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from pyrobots_aio import ActionCancelled, ActionHandle, Robot, action

THROUGHPUT_N = 20_000
ROUNDS = 7
BATCH = 2_000
LATENCY_N = 2_000
SLEEPERS = 100_000
CANCEL_ALL = (1_000, 10_000)
WORK_N = 200_000
INTROSPECTED = 1_000


@action
async def nop(robot: Robot) -> int:
    return 1


async def bare_nop() -> int:
    return 1


@action
async def sleeper(robot: Robot) -> None:
    await asyncio.sleep(3600)


async def bare_sleeper() -> None:
    await asyncio.sleep(3600)


def _work(n: int) -> int:
    total = 0
    for i in range(n):
        total += i * i % 7
    return total


@action
async def work_action(robot: Robot, n: int) -> int:
    return _work(n)


def _rss_bytes() -> int:
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * 4096


async def _throughput(robot: Robot) -> dict[str, float]:
    """One by one, actions and bare tasks in turn, ROUNDS times: the best of each is compared.

    A single pass of each swings by 10 % on this shared machine; taking each
    side's best of several interleaved passes (as ``timeit`` does) leaves the
    noise out of the ratio, and the median of the per-round ratios is beside it.
    """
    action_best = bare_best = float("inf")
    ratios = []
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for _ in range(THROUGHPUT_N):
            await nop(robot)
        action_s = time.perf_counter() - start
        start = time.perf_counter()
        for _ in range(THROUGHPUT_N):
            await asyncio.create_task(bare_nop())
        bare_s = time.perf_counter() - start
        ratios.append(action_s / bare_s)
        action_best, bare_best = min(action_best, action_s), min(bare_best, bare_s)
    start = time.perf_counter()
    for _ in range(THROUGHPUT_N // BATCH):  # batches short enough not to alarm the watchdog
        handles = [nop(robot) for _ in range(BATCH)]
        for handle in handles:
            await handle
    batch_s = time.perf_counter() - start
    return {
        "throughput_actions_per_s": THROUGHPUT_N / action_best,
        "throughput_bare_tasks_per_s": THROUGHPUT_N / bare_best,
        "throughput_ratio_vs_bare": action_best / bare_best,
        "throughput_ratio_vs_bare_median": statistics.median(ratios),
        "throughput_batch_actions_per_s": THROUGHPUT_N / batch_s,
    }


async def _cancel_latency(robot: Robot) -> dict[str, float]:
    samples: list[int] = []
    marks: dict[str, int] = {}

    @action
    async def victim(robot: Robot) -> None:
        try:
            await asyncio.sleep(3600)
        except ActionCancelled:
            samples.append(time.perf_counter_ns() - marks["cancel"])
            raise

    for _ in range(LATENCY_N):
        handle = victim(robot)
        await asyncio.sleep(0)
        marks["cancel"] = time.perf_counter_ns()
        handle.cancel("bench")
        await handle.wait_done()
    bare: list[int] = []

    async def bare_victim() -> None:
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            bare.append(time.perf_counter_ns() - marks["cancel"])
            raise

    for _ in range(LATENCY_N):
        task = asyncio.create_task(bare_victim())
        await asyncio.sleep(0)
        marks["cancel"] = time.perf_counter_ns()
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
    return {
        "cancel_to_handler_median_us": statistics.median(samples) / 1e3,
        "cancel_to_handler_p99_us": _p99(samples) / 1e3,
        "cancel_to_handler_bare_p99_us": _p99(bare) / 1e3,
    }


async def _memory(robot: Robot) -> dict[str, float]:
    """RSS per sleeper, each kind in a fresh interpreter (a freed heap would be reused)."""
    handles = [sleeper(robot) for _ in range(SLEEPERS)]
    await asyncio.sleep(0.01)
    start = time.perf_counter()
    await robot.cancel_all("bench")
    cancel_s = time.perf_counter() - start
    assert all(h.done() for h in handles)
    return {
        "concurrent_sleeping_actions": float(SLEEPERS),
        "rss_per_sleeping_action_kib": _rss_in_fresh_process("action") / 1024,
        "rss_per_bare_task_kib": _rss_in_fresh_process("bare") / 1024,
        f"cancel_all_{SLEEPERS}_s": cancel_s,
    }


def _rss_in_fresh_process(kind: str) -> float:
    """Bytes of RSS per sleeping ``kind`` ("action" or "bare"), measured in a new interpreter."""
    done = subprocess.run(
        [sys.executable, "-m", "tests.bench.bench_actions", "rss", kind],
        capture_output=True,
        text=True,
        check=True,
    )
    return float(done.stdout)


async def _rss_per_sleeper(kind: str) -> float:
    async with Robot(block_threshold=None) as robot:  # (starting 100,000 blocks on purpose)
        gc.collect()
        before = _rss_bytes()
        if kind == "action":
            sleepers: list[ActionHandle[None] | asyncio.Task[None]] = [
                sleeper(robot) for _ in range(SLEEPERS)
            ]
        else:
            sleepers = [asyncio.create_task(bare_sleeper()) for _ in range(SLEEPERS)]
        await asyncio.sleep(0.01)
        gc.collect()
        per_sleeper = (_rss_bytes() - before) / SLEEPERS
        for one in sleepers:
            one.cancel()
        await asyncio.sleep(0.01)
    return per_sleeper


async def _cancel_all(robot: Robot) -> dict[str, float]:
    figures = {}
    for count in CANCEL_ALL:
        handles = [sleeper(robot) for _ in range(count)]
        await asyncio.sleep(0)
        start = time.perf_counter()
        await robot.cancel_all("bench")
        figures[f"cancel_all_{count}_s"] = time.perf_counter() - start
        assert all(h.done() for h in handles)
    return figures


async def _python_work(robot: Robot) -> dict[str, float]:
    plain, inside = [], []
    for _ in range(5):  # best of five of each: the machine is shared and noisy
        start = time.perf_counter()
        _work(WORK_N)
        plain.append(time.perf_counter() - start)
        start = time.perf_counter()
        await work_action(robot, WORK_N)
        inside.append(time.perf_counter() - start)
    return {"python_work_inside_action_ratio": min(inside) / min(plain)}


def _p99(samples: list[int]) -> float:
    ordered = sorted(samples)
    return float(ordered[int(0.99 * (len(ordered) - 1))])


async def _introspection(robot: Robot) -> dict[str, float]:
    """``robot.running()`` and the printed tree with 1,000 running actions (best of 50)."""
    handles = [sleeper(robot) for _ in range(INTROSPECTED)]
    await asyncio.sleep(0)
    figures = {}
    for name, call in (
        ("running", robot.running),
        ("action_tree", robot.action_tree),
        ("running_with_locations", lambda: [info.location for info in robot.running()]),
    ):
        best = min(_timed(call) for _ in range(50))
        figures[f"{name}_{INTROSPECTED}_ms"] = best * 1e3
    await robot.cancel_all("bench")
    assert all(h.done() for h in handles)
    return figures


def _timed(call: Callable[[], object]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


async def _main() -> dict[str, float]:
    figures: dict[str, float] = {}
    async with Robot() as robot:  # as a user gets it: the loop watchdog on
        for part in (_python_work, _throughput, _cancel_latency):
            figures.update(await part(robot))
    # Starting, listing and cancelling thousands of actions at once blocks the loop on
    # purpose: no watchdog, whose reports would only say so.
    async with Robot(block_threshold=None) as robot:
        for part in (_cancel_all, _introspection, _memory):
            figures.update(await part(robot))
    return figures


def run() -> dict[str, float]:
    """Measure the executive; return the figures."""
    return asyncio.run(_main())


if __name__ == "__main__":  # python -m tests.bench.bench_actions rss action|bare
    print(asyncio.run(_rss_per_sleeper(sys.argv[2])))
