"""Benchmarks of event monitors (DESIGN.md §10), beside a py_trees tree when installed.

Every figure comes from a real asyncio loop and the wall clock (this is a
benchmark, not a test). ``run()`` returns them in a flat dict:

- ``write_to_callback_*``: a state write until the callback runs (plain and
  coroutine callbacks, ``LATENCY_N`` samples each);
- ``pulses_seen_of_30``: 30 pulses of 20 ms on a real-time loop;
- ``idle_cpu_s_per_s_1000_monitors``: CPU time per second while 1,000
  monitors watch a state that does not change;
- ``writes_per_s_*``: state write throughput with 1,000 monitors attached;
- ``unsubscribe_us_each_*``: closing every one of that many subscriptions
  of one key, per subscription (it should not grow with their number);
- ``py_trees_*``: a py_trees tree with the same condition ticking at 10 Hz and
  as fast as it can, under the same writer as ``events_harness_*`` (skipped,
  with ``py_trees_available`` 0, when py_trees is not installed).
"""

from __future__ import annotations

import asyncio
import gc
import operator
import random
import statistics
import time
from typing import TYPE_CHECKING, Any

from pyrobots_aio import Robot

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

LATENCY_N = 2_000
PULSES = 30
MONITORS = 1_000
IDLE_SECONDS = 2.0
WRITES = 20_000
HARNESS = {"10hz": (0.1, 40), "max_rate": (0.0, 400)}  # tick period, samples


def _p99(samples: list[float]) -> float:
    ordered = sorted(samples)
    return ordered[int(0.99 * (len(ordered) - 1))]


def _stats(prefix: str, samples_ns: list[float]) -> dict[str, float]:
    return {
        f"{prefix}_median_us": statistics.median(samples_ns) / 1e3,
        f"{prefix}_p99_us": _p99(samples_ns) / 1e3,
    }


# -- write -> callback latency ----------------------------------------------------------


async def _latency(robot: Robot, coroutine: bool) -> list[float]:
    samples: list[float] = []
    mark = [0]
    done: list[asyncio.Future[None]] = []

    def plain() -> None:
        samples.append(time.perf_counter_ns() - mark[0])
        done[0].set_result(None)

    async def coro() -> None:
        plain()

    # blocking=False: the next press may come while the coroutine callback's task is still
    # winding up, and a blocking monitor would (rightly) drop that firing.
    monitor = robot.whenever("button", becomes=True, blocking=False)
    monitor.do(coro if coroutine else plain)
    loop = asyncio.get_running_loop()
    for _ in range(LATENCY_N):
        done[:] = [loop.create_future()]
        mark[0] = time.perf_counter_ns()
        robot.state.button = True
        await done[0]
        robot.state.button = False
    await monitor.close()
    return samples


async def _latencies(robot: Robot) -> dict[str, float]:
    robot.state.button = False
    plain = await _latency(robot, coroutine=False)
    coro = await _latency(robot, coroutine=True)
    return {
        **_stats("write_to_callback", plain + coro),
        **_stats("write_to_plain_callback", plain),
        **_stats("write_to_coroutine_callback", coro),
        "write_to_callback_samples": float(len(plain) + len(coro)),
    }


# -- pulses -------------------------------------------------------------------------------


async def _pulses(robot: Robot) -> dict[str, float]:
    robot.state.pulse = False
    edge = robot.whenever("pulse", becomes=True)
    level = robot.whenever("pulse", value=True)
    for _ in range(PULSES):
        robot.state.pulse = True
        await asyncio.sleep(0.02)
        robot.state.pulse = False
        await asyncio.sleep(0.08)
    seen = (edge.firings, level.firings)
    await edge.close()
    await level.close()
    return {"pulses_seen_of_30": float(seen[0]), "pulses_seen_of_30_level": float(seen[1])}


# -- idle CPU, write throughput -----------------------------------------------------------


def _many_monitors(robot: Robot, keys: list[str]) -> None:
    """1,000 monitors of every kind, none of whose conditions holds."""
    for i in range(MONITORS):
        key = keys[i % len(keys)]
        kind = i % 5
        if kind == 0:
            robot.whenever(key, becomes=-1.0)
        elif kind == 1:
            robot.whenever(key, below=-1.0)
        elif kind == 2:
            robot.whenever(key, increase=1e9)
        elif kind == 3:
            robot.whenever(key, above=1e9, held_for=1.0)
        else:
            robot.whenever(_below(key, -1.0))


def _below(key: str, limit: float) -> Callable[[Robot], bool]:
    """A condition as a plain predicate: ``robot.state[key] < limit``."""

    def below(robot: Robot) -> bool:
        return bool(robot.state[key] < limit)

    return below


async def _idle(robot: Robot) -> dict[str, float]:
    keys = [f"sensor_{i}" for i in range(MONITORS)]
    robot.state.update(dict.fromkeys(keys, 0.0))
    _many_monitors(robot, keys)
    await asyncio.sleep(0.1)
    gc.collect()
    cpu, wall = time.process_time(), time.perf_counter()
    await asyncio.sleep(IDLE_SECONDS)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    await robot.events.cancel_all()
    return {"idle_cpu_s_per_s_1000_monitors": cpu / wall}


def _writes_per_s(robot: Robot, key: str, writes: int = WRITES) -> float:
    state = robot.state
    start = time.perf_counter()
    for i in range(writes):
        state[key] = float(i)
    return writes / (time.perf_counter() - start)


async def _throughput(robot: Robot) -> dict[str, float]:
    robot.state.update(free=0.0, shared=0.0, other=0.0)
    bare = _writes_per_s(robot, "free")
    _many_monitors(robot, ["other"])
    other = _writes_per_s(robot, "free")
    await robot.events.cancel_all()
    _many_monitors(robot, ["shared"])
    same = _writes_per_s(robot, "shared", WRITES // 20)  # each write tests 1,000 conditions
    await robot.events.cancel_all()
    return {
        "writes_per_s_no_monitors": bare,
        "writes_per_s_1000_monitors": other,
        "writes_per_s_1000_monitors_same_key": same,
    }


# -- the same condition under one writer: our monitor and a py_trees tree ----------------------


async def _writer(
    samples: int, press: Callable[[bool], None], reacted: Callable[[], Awaitable[None]]
) -> tuple[list[float], float]:
    """Press, wait for the reaction, release, pause at random; return latencies and CPU s/s."""
    rng = random.Random(0)
    latencies: list[float] = []
    cpu, wall = time.process_time(), time.perf_counter()
    for _ in range(samples):
        await asyncio.sleep(rng.uniform(0.005, 0.05))
        start = time.perf_counter_ns()
        press(True)
        await reacted()
        latencies.append(time.perf_counter_ns() - start)
        press(False)
    return latencies, (time.process_time() - cpu) / (time.perf_counter() - wall)


async def _events_harness(robot: Robot, samples: int) -> dict[str, float]:
    robot.state.lever = False
    reaction: list[asyncio.Future[None]] = []

    def react() -> None:
        reaction[0].set_result(None)

    async def reacted() -> None:
        await reaction[0]

    def press(down: bool) -> None:
        if down:
            reaction[:] = [asyncio.get_running_loop().create_future()]
        robot.state.lever = down

    monitor = robot.whenever("lever", becomes=True).do(react)
    latencies, cpu = await _writer(samples, press, reacted)
    await monitor.close()
    return {**_stats("events_harness_latency", latencies), "events_harness_cpu_s_per_s": cpu}


async def _py_trees(mode: str, period: float, samples: int) -> dict[str, float]:
    import py_trees

    py_trees.blackboard.Blackboard.clear()
    writer = py_trees.blackboard.Client(name="writer")
    writer.register_key(key="lever", access=py_trees.common.Access.WRITE)
    writer.lever = False
    reaction: list[asyncio.Future[None]] = []

    class React(py_trees.behaviour.Behaviour):
        def update(self) -> Any:
            if reaction and not reaction[0].done():
                reaction[0].set_result(None)
            return py_trees.common.Status.SUCCESS

    check = py_trees.common.ComparisonExpression("lever", True, operator.eq)
    root = py_trees.composites.Sequence(
        "reflex",
        memory=False,
        children=[py_trees.behaviours.CheckBlackboardVariableValue("pressed?", check), React("r")],
    )
    tree = py_trees.trees.BehaviourTree(root)
    stop = asyncio.Event()

    async def tick() -> None:
        while not stop.is_set():
            tree.tick()
            await asyncio.sleep(period)

    def press(down: bool) -> None:
        if down:
            reaction[:] = [asyncio.get_running_loop().create_future()]
        writer.lever = down

    async def reacted() -> None:
        await reaction[0]

    ticker = asyncio.create_task(tick())
    latencies, cpu = await _writer(samples, press, reacted)
    stop.set()
    await ticker
    return {
        **_stats(f"py_trees_{mode}_latency", latencies),
        f"py_trees_{mode}_cpu_s_per_s": cpu,
    }


async def _unsubscribe(robot: Robot) -> dict[str, float]:
    figures = {}
    for count in (100, 10_000):
        subs = [robot.state.subscribe(len, keys="crowded") for _ in range(count)]
        robot.state.crowded = 0  # (a snapshot of the crowd is taken)
        start = time.perf_counter()
        for sub in subs:
            sub.close()
        figures[f"unsubscribe_us_each_{count}"] = (time.perf_counter() - start) / count * 1e6
    return figures


async def _side_by_side(robot: Robot) -> dict[str, float]:
    figures = await _events_harness(robot, HARNESS["10hz"][1])
    try:
        import py_trees  # noqa: F401
    except ImportError:
        return {**figures, "py_trees_available": 0.0}
    for mode, (period, samples) in HARNESS.items():
        figures.update(await _py_trees(mode, period, samples))
    return {**figures, "py_trees_available": 1.0}


async def _main() -> dict[str, float]:
    figures: dict[str, float] = {}
    # No loop watchdog: the parts that build or tear down thousands of monitors block on purpose.
    async with Robot(block_threshold=None) as robot:
        for part in (_latencies, _pulses, _idle, _throughput, _unsubscribe, _side_by_side):
            figures.update(await part(robot))
    return figures


def run() -> dict[str, float]:
    """Measure the event monitors (and py_trees beside them, if installed); return the figures."""
    return asyncio.run(_main())


if __name__ == "__main__":
    for name, value in run().items():
        print(f"{name:48} {value:14.3f}")
