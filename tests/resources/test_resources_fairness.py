"""Fairness under contention (issue 16 item 7): no head-of-line blocking, aging against starvation.

In virtual time. The policy is in `ResourceManager`'s docstring and `_rules`.
"""

from __future__ import annotations

import math

import pytest

from pyrobots_aio import LockUsageError, Resource, Robot, action, lock
from pyrobots_aio.resources import CompoundResource, _rules

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

A, B, C = Resource("a"), Resource("b"), Resource("c")
AB = CompoundResource(A, B, name="ab")


@action
async def hold(
    robot: Robot,
    resource: Resource | CompoundResource,
    seconds: float,
    log: list[str],
    name: str,
    *,
    priority: int = 0,
) -> float:
    async with lock(resource, priority=priority):
        log.append(f"{robot.time():g} {name}")
        await robot.sleep(seconds)
    return robot.time()


async def test_a_request_on_an_idle_resource_is_granted_while_a_held_up_compound_waits() -> None:
    log: list[str] = []
    async with Robot() as robot:
        hold(robot, A, 10, log, "a holder")
        await robot.sleep(1)
        compound = hold(robot, AB, 1, log, "compound")
        await robot.sleep(1)
        assert robot.resources.waiters(B) == [compound]
        single = hold(robot, B, 3, log, "b user")  # B is idle: it need not wait 8 s
        await robot.sleep(0)
        assert robot.resources.owner(B) is single
        late = hold(robot, B, 1, log, "late b user")
        assert await compound == 11
        await late
    assert log == [
        "0 a holder",
        "2 b user",  # on main: at 11 (B stayed idle 8 s, promised to the compound)
        "5 late b user",  # the compound is still held up by the holder of A
        "10 compound",  # the holder of A is done: served at once
    ]


async def test_once_free_of_its_holders_the_compound_goes_before_later_requests() -> None:
    log: list[str] = []
    async with Robot() as robot:
        hold(robot, A, 2, log, "a holder")
        await robot.sleep(0.5)
        compound = hold(robot, AB, 1, log, "compound")
        await robot.sleep(0.5)
        hold(robot, B, 5, log, "slow b user")  # runs past the A holder: the compound waits
        await robot.sleep(1.5)
        others = [hold(robot, B, 1, log, f"b{i}") for i in range(3)]
        hold(robot, C, 1, log, "c user")
        assert await compound == 7
        for other in others:
            await other
    assert log == [
        "0 a holder",
        "1 slow b user",
        "2.5 c user",  # C conflicts with nobody
        "6 compound",  # after the one hold taken meanwhile, before b0..b2
        "7 b0",
        "8 b1",
        "9 b2",
    ]


async def test_a_held_up_request_is_passed_at_most_bypass_limit_times() -> None:
    log: list[str] = []
    limit = _rules.BYPASS_LIMIT
    async with Robot() as robot:
        hold(robot, A, 100, log, "a holder")
        await robot.sleep(0.5)
        compound = hold(robot, AB, 1, log, "compound")
        users = []
        for i in range(limit + 2):
            await robot.sleep(1)
            users.append(hold(robot, B, 0.5, log, f"b{i}"))
        assert await compound == 101
        for user in users:
            await user
    passed = [f"{1.5 + i:g} b{i}" for i in range(limit)]
    assert log == [
        "0 a holder",
        *passed,  # B would have stayed idle for 100 s
        "100 compound",  # then it kept its place: the next B users wait for it
        f"101 b{limit}",
        f"101.5 b{limit + 1}",
    ]


@action
async def worker(robot: Robot, priority: int, until: float, served: list[str]) -> None:
    while robot.time() < until:
        async with lock(A, priority=priority):
            served.append(f"p{priority}")
            await robot.sleep(1)


@action
async def low(robot: Robot) -> float:
    start = robot.time()
    async with lock(A, priority=0):
        return robot.time() - start


async def test_strict_priority_starves_a_low_priority_request() -> None:
    async with Robot() as robot:
        assert robot.resources.aging is None  # the default: strict priority
        served: list[str] = []
        workers = [worker(robot, 5, 300, served) for _ in range(3)]
        await robot.sleep(0.5)
        waited = await low(robot)
        for handle in workers:
            await handle
    assert waited > 299  # served only once the workers stopped
    assert served.count("p5") >= 299


async def test_with_aging_a_low_priority_request_is_served_within_a_bound() -> None:
    async with Robot() as robot:
        robot.resources.aging = 2.0  # 2 s of waiting is worth one priority level
        served: list[str] = []
        workers = [worker(robot, 5, 300, served) for _ in range(3)]
        await robot.sleep(0.5)
        waited = await low(robot)
        for handle in workers:
            await handle
    # Priority 0 outranks a fresh priority-5 request after 5 levels * 2 s = 10 s of waiting;
    # then it waits for those queued before (one per worker, 1 s each): within 13 s.
    assert 10 < waited <= 13
    assert served.count("p5") >= 280  # the high priorities still get nearly everything


async def test_aging_never_lets_a_later_lower_priority_overtake_and_short_waits_keep_priority() -> (
    None
):
    log: list[str] = []
    async with Robot() as robot:
        robot.resources.aging = 1.0
        hold(robot, A, 4, log, "holder")
        await robot.sleep(0.5)
        hold(robot, A, 1, log, "early high", priority=3)
        await robot.sleep(0.5)
        hold(robot, A, 1, log, "later low", priority=0)  # ranks 3 levels below, for ever
        await robot.sleep(2.5)  # waited 2.5 s < 3 s: a fresh priority 3 still wins
        fresh = hold(robot, A, 1, log, "fresh high", priority=3)
        await fresh
        await robot.sleep(5)
    assert log == ["0 holder", "4 early high", "5 fresh high", "6 later low"]


@pytest.mark.parametrize("bad", [0, -1.0, math.inf, math.nan, True, "2"])
async def test_a_bad_aging_is_refused_naming_it(bad: object) -> None:
    async with Robot() as robot:
        with pytest.raises(LockUsageError, match=r"^aging must be a positive number of seconds"):
            robot.resources.aging = bad  # type: ignore[assignment]
        assert robot.resources.aging is None


async def test_aging_cannot_change_while_requests_wait() -> None:
    log: list[str] = []
    async with Robot() as robot:
        hold(robot, A, 1, log, "holder")
        waiter = hold(robot, A, 1, log, "waiter")
        await robot.sleep(0)
        with pytest.raises(LockUsageError) as info:
            robot.resources.aging = 5
        assert str(info.value) == (
            "cannot change aging to 5 while 1 requests wait; set it before they queue "
            "(e.g. at the start)"
        )
        await waiter
        robot.resources.aging = 5
        assert robot.resources.aging == 5.0
