"""Benchmarks of resource arbitration (DESIGN.md §10: resource hand-off p99 <= 0.5 ms).

``run()`` returns the figures in a flat dict:

- ``handoff_median_us`` / ``handoff_p99_us``: an action locking the wheels ends
  its body -> the next queued action's body runs (2,000 queued ``@lock`` actions;
  the executive's wind-up of the holder included).
- ``pingpong_median_us`` / ``pingpong_p99_us``: two actions alternating on
  ``async with lock(WHEELS)``; block exit -> the other's block entry.
- ``acquire_release_free_us_with_1000_waiters``: acquire + release of a free
  resource while 1,000 requests wait for another one.
- ``drain_us_per_waiter_1000`` / ``drain_us_per_waiter_10``: a holder releases,
  then 1,000 (or 10) queued waiters each acquire and release in turn; per waiter.
  Close values mean a hand-off does not grow with the queue.
- ``drain_compound_us_per_waiter_1000``: the same with every other waiter asking
  for a compound of two resources.
- ``utilisation_pct_compound_contention``: 24 actions contend for 6 resources
  for 600 virtual seconds, each request a random resource or compound of 2-3
  (seeded), priority 0-2, held 0.5-2 s: the share of resource-seconds held.
  Held-up requests are skipped (no head-of-line blocking): before that, a
  queued compound kept its free resources idle (the issue measured ~40 % idle).
- ``max_wait_lowest_priority_s_strict`` / ``max_wait_lowest_priority_s_aging``:
  the longest wait of a priority-0 request in that run, with strict priority
  and with ``robot.resources.aging = 2.0`` (2 s of waiting per level).
"""

from __future__ import annotations

import asyncio
import random
import statistics
import time
from typing import TYPE_CHECKING

from pyrobots_aio import Robot, action
from pyrobots_aio.actions import lock
from pyrobots_aio.loops import run_lockstep
from pyrobots_aio.resources import CompoundResource, Resource, ResourceManager

if TYPE_CHECKING:
    from collections.abc import Callable

WHEELS, ARM = Resource("wheels"), Resource("arm")
BOTH = CompoundResource(WHEELS, ARM, name="both")
HANDOFFS = 2000


class _Owner:
    """The least an owner needs (stands in for an action handle)."""

    def __init__(self, ident: int) -> None:
        self.id = ident
        self.name = "owner"
        self.parent: _Owner | None = None
        self.held: tuple[str, ...] = ()
        self.awaiting: tuple[str, ...] = ()

    cancel_requested = False

    def cancel(self, reason: str | None = None) -> bool:
        return True

    def done(self) -> bool:
        return False

    def add_finalizer(self, finalizer: Callable[[], None]) -> None:
        pass

    def _suspend(self, reason: str, by: object) -> None:
        pass

    def _unsuspend(self) -> None:
        pass


def _percentiles(samples_ns: list[int]) -> tuple[float, float]:
    ordered = sorted(samples_ns)
    p99 = ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))]
    return statistics.median(ordered) / 1e3, p99 / 1e3


@action
@lock(WHEELS)
async def _step(robot: Robot, i: int, starts: list[int], ends: list[int]) -> None:
    starts[i] = time.perf_counter_ns()
    await asyncio.sleep(0)
    ends[i] = time.perf_counter_ns()


async def _handoff() -> tuple[float, float]:
    n = HANDOFFS + 1
    starts, ends = [0] * n, [0] * n
    async with Robot() as robot:
        handles = [_step(robot, i, starts, ends) for i in range(n)]
        for handle in handles:
            await handle
    return _percentiles([starts[i + 1] - ends[i] for i in range(HANDOFFS)])


@action
async def _pinger(robot: Robot, rounds: int, exits: list[int], entries: list[int]) -> None:
    for _ in range(rounds):
        async with lock(WHEELS):
            entries.append(time.perf_counter_ns())
            await asyncio.sleep(0)
            exits.append(time.perf_counter_ns())


async def _pingpong() -> tuple[float, float]:
    exits: list[int] = []
    entries: list[int] = []
    async with Robot() as robot:
        rounds = HANDOFFS // 2 + 1
        await asyncio.gather(
            _pinger(robot, rounds, exits, entries).wait(),
            _pinger(robot, rounds, exits, entries).wait(),
        )
    return _percentiles([entries[i + 1] - exits[i] for i in range(len(exits) - 1)])


async def _queue(
    manager: ResourceManager[_Owner], n: int, pattern: tuple[Resource | CompoundResource, ...]
) -> list[asyncio.Task[None]]:
    async def waiter(i: int) -> None:
        grant = await manager.acquire(_Owner(i), pattern[i % len(pattern)])
        grant.release()

    tasks = [asyncio.create_task(waiter(i)) for i in range(n)]
    await asyncio.sleep(0)
    return tasks


async def _free_with_waiters() -> float:
    manager: ResourceManager[_Owner] = ResourceManager()
    blocker = await manager.acquire(_Owner(-1), WHEELS)
    tasks = await _queue(manager, 1000, (WHEELS,))
    owner = _Owner(-2)
    rounds = 20_000
    t0 = time.perf_counter_ns()
    for _ in range(rounds):
        (await manager.acquire(owner, ARM)).release()
    elapsed = time.perf_counter_ns() - t0
    blocker.release()
    await asyncio.gather(*tasks)
    return elapsed / rounds / 1e3


async def _drain(n: int, pattern: tuple[Resource | CompoundResource, ...]) -> float:
    manager: ResourceManager[_Owner] = ResourceManager()
    blocker = await manager.acquire(_Owner(-1), BOTH)
    tasks = await _queue(manager, n, pattern)
    t0 = time.perf_counter_ns()
    blocker.release()
    await asyncio.gather(*tasks)
    return (time.perf_counter_ns() - t0) / n / 1e3


POOL = tuple(Resource(f"r{i}") for i in range(6))
CONTENTION_SECONDS = 600.0


@action
async def _contender(
    robot: Robot, rng: random.Random, held: list[float], waits: dict[int, list[float]]
) -> None:
    while robot.time() < CONTENTION_SECONDS:
        parts = rng.sample(POOL, rng.choice((1, 1, 2, 3)))
        wanted = parts[0] if len(parts) == 1 else CompoundResource(*parts)
        priority, seconds = rng.randint(0, 2), rng.uniform(0.5, 2.0)
        asked = robot.time()
        async with lock(wanted, priority=priority):
            waits[priority].append(robot.time() - asked)
            await robot.sleep(seconds)
            held.append(seconds * len(parts))


async def _contention(aging: float | None) -> tuple[float, float]:
    rng = random.Random(16)
    held: list[float] = []
    waits: dict[int, list[float]] = {0: [], 1: [], 2: []}
    async with Robot() as robot:
        robot.resources.aging = aging
        workers = [_contender(robot, rng, held, waits) for _ in range(24)]
        for worker in workers:
            await worker
        elapsed = robot.time()
    return 100 * sum(held) / (len(POOL) * elapsed), max(waits[0])


def run() -> dict[str, float]:
    """Run every resource benchmark; return the figures (microseconds)."""
    handoff_median, handoff_p99 = asyncio.run(_handoff())
    ping_median, ping_p99 = asyncio.run(_pingpong())
    figures = {
        "handoff_median_us": handoff_median,
        "handoff_p99_us": handoff_p99,
        "pingpong_median_us": ping_median,
        "pingpong_p99_us": ping_p99,
        "acquire_release_free_us_with_1000_waiters": asyncio.run(_free_with_waiters()),
        "drain_us_per_waiter_1000": asyncio.run(_drain(1000, (WHEELS,))),
        "drain_us_per_waiter_10": asyncio.run(_drain(10, (WHEELS,))),
        "drain_compound_us_per_waiter_1000": asyncio.run(_drain(1000, (WHEELS, BOTH))),
    }
    utilisation, strict = run_lockstep(_contention, None)
    _, aged = run_lockstep(_contention, 2.0)
    figures["utilisation_pct_compound_contention"] = utilisation
    figures["max_wait_lowest_priority_s_strict"] = strict
    figures["max_wait_lowest_priority_s_aging"] = aged
    return figures
