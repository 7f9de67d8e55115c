"""Lock cycles: nested locks in opposite orders raise `ResourceDeadlockError` instead of hanging.

In virtual time. The action whose request would close the cycle gets the
error; the others go on once it has let go of what it holds.
"""

from __future__ import annotations

import asyncio

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pyrobots_aio import (
    ActionHandle,
    CompoundResource,
    EventKind,
    Outcome,
    Resource,
    ResourceDeadlockError,
    ResourceError,
    Robot,
    action,
    lock,
)
from pyrobots_aio.sim import run
from pyrobots_aio.testing import EventLog

virtual = pytest.mark.virtual_time

A, B, C = Resource("a"), Resource("b"), Resource("c")


@action
async def nested(robot: Robot, first: Resource, second: Resource, log: list[str]) -> str:
    async with lock(first):
        await robot.sleep(1)
        async with lock(second):
            log.append(f"{robot.time():g} {first.name}{second.name}")
            await robot.sleep(1)
    return "done"


def who(handle: ActionHandle[object]) -> str:
    return f"nested#{handle.id}"


@pytest.mark.asyncio
@virtual
async def test_opposite_orders_one_gets_the_error_the_other_proceeds() -> None:
    log: list[str] = []
    events = EventLog()
    async with Robot(instruments=[events]) as robot:
        ab = nested(robot, A, B, log)
        ba = nested(robot, B, A, log)
        assert await ab.wait_done() is Outcome.SUCCEEDED
        assert await ba.wait_done() is Outcome.FAILED
        error = ba.exception()
        assert repr(robot.resources) == "<ResourceManager idle>"
    assert isinstance(error, ResourceDeadlockError)
    assert isinstance(error, ResourceError)
    assert str(error) == (
        f"lock cycle (deadlock): {who(ba)} waits for 'a' held by {who(ab)}; "
        f"{who(ab)} waits for 'b' held by {who(ba)}; take the resources in one order "
        "everywhere, or together as one CompoundResource"
    )
    assert error.cycle == ((ba, "a", ab), (ab, "b", ba))
    assert log == ["1 ab"]  # at once: the refused action let go of b
    skipped = events.first(EventKind.RESOURCE_SKIPPED)
    assert skipped.data["deadlock"] == [[ba.id, "a", ab.id], [ab.id, "b", ba.id]]


@pytest.mark.asyncio
@virtual
async def test_a_three_party_cycle_is_refused_to_the_action_that_closes_it() -> None:
    log: list[str] = []

    @action
    async def late(robot: Robot, first: Resource, second: Resource, delay: float) -> None:
        async with lock(first):
            await robot.sleep(delay)
            async with lock(second):
                log.append(f"{robot.time():g} {first.name}{second.name}")

    async with Robot() as robot:
        ab = late(robot, A, B, 1)
        bc = late(robot, B, C, 1.1)
        ca = late(robot, C, A, 1.2)  # closes a -> b -> c -> a
        outcomes = [await h.wait_done() for h in (ab, bc, ca)]
        error = ca.exception()
    assert outcomes == [Outcome.SUCCEEDED, Outcome.SUCCEEDED, Outcome.FAILED]
    assert isinstance(error, ResourceDeadlockError)
    assert [(w.id, r, h.id) for w, r, h in error.cycle] == [
        (ca.id, "a", ab.id),
        (ab.id, "b", bc.id),
        (bc.id, "c", ca.id),
    ]
    assert log == ["1.2 bc", "1.2 ab"]


@action
@lock(B)
async def lock_b(robot: Robot) -> None:
    await robot.sleep(1)


@action
@lock(A)
async def lock_a(robot: Robot) -> None:
    await robot.sleep(1)


@action
@lock(A)
async def a_then_child_b(robot: Robot) -> None:
    await robot.sleep(1)
    await lock_b(robot)


@action
@lock(B)
async def b_then_child_a(robot: Robot) -> None:
    await robot.sleep(1.5)
    await lock_a(robot)


@pytest.mark.asyncio
@virtual
async def test_locked_actions_whose_children_lock_in_opposite_orders() -> None:
    async with Robot() as robot:
        first = a_then_child_b(robot)
        second = b_then_child_a(robot)
        assert await first.wait_done() is Outcome.SUCCEEDED
        assert await second.wait_done() is Outcome.FAILED
    error = second.exception()
    assert isinstance(error, ResourceDeadlockError)  # raised in its child, re-raised by it
    (waiter, resource, holder), (waiter2, resource2, holder2) = error.cycle
    assert (waiter.name, resource, holder) == ("lock_a", "a", first)
    assert (waiter2.name, resource2, holder2) == ("lock_b", "b", second)


@pytest.mark.asyncio
@virtual
async def test_no_cycle_when_the_holder_can_let_go_without_the_request() -> None:
    """Its child waits for b, but the holder's ``async with`` block ends on its own."""
    log: list[str] = []

    @action
    async def child_b(robot: Robot) -> None:
        async with lock(B):
            log.append(f"{robot.time():g} child has b")

    @action
    async def a_block_with_a_child(robot: Robot) -> None:
        async with lock(A):
            child = child_b(robot)  # not awaited in the block
            await robot.sleep(2)
        log.append(f"{robot.time():g} a released")
        await child

    @action
    async def b_then_a(robot: Robot) -> None:
        async with lock(B):
            await robot.sleep(1)
            async with lock(A):
                log.append(f"{robot.time():g} b then a")

    async with Robot() as robot:
        first = a_block_with_a_child(robot)
        second = b_then_a(robot)
        assert [await h.wait_done() for h in (first, second)] == [Outcome.SUCCEEDED] * 2
    assert log == ["2 a released", "2 b then a", "2 child has b"]


@pytest.mark.asyncio
@virtual
async def test_a_preempting_request_closes_no_cycle() -> None:
    @action
    async def urgent(robot: Robot) -> str:
        async with lock(B):
            await robot.sleep(1)
            async with lock(A, priority=5, preempt=True):
                return "took a"

    async with Robot() as robot:
        ab = nested(robot, A, B, [])
        assert await urgent(robot) == "took a"  # it cancels the holder instead
        assert await ab.wait_done() is Outcome.CANCELLED


@pytest.mark.asyncio
@virtual
async def test_the_refused_action_can_recover_with_a_compound() -> None:
    log: list[str] = []

    @action
    async def careful(robot: Robot) -> None:
        try:
            async with lock(B):
                await robot.sleep(1)
                async with lock(A):
                    log.append("never")
        except ResourceDeadlockError:
            async with lock(CompoundResource(A, B)):
                log.append(f"{robot.time():g} both at once")

    async with Robot() as robot:
        ab = nested(robot, A, B, log)
        await careful(robot)
        await ab
    assert log == ["1 ab", "2 both at once"]


# -- property: random nested locks never hang, and only real cycles are refused --------


async def run_nested(specs: list[tuple[int, int, int, int]]) -> None:
    pool = (A, B, C)
    refused: list[ResourceDeadlockError] = []

    @action
    async def two(robot: Robot, first: Resource, second: Resource, hold: int, gap: int) -> None:
        async with lock(first):
            for _ in range(gap):
                await robot.sleep(0.1)
            try:
                async with lock(second):
                    await robot.sleep(0.1 * hold)
            except ResourceDeadlockError as error:
                refused.append(error)
                # a real cycle: each step's holder holds the resource and waits in turn
                for (_, name, holder), (waiter, _, _) in zip(
                    error.cycle, error.cycle[1:] + error.cycle[:1], strict=True
                ):
                    assert waiter is holder or waiter.childof(holder)
                    assert robot.resources.owner(Resource(name)) is holder
                raise

    async with Robot() as robot:
        handles = [
            two(robot, pool[f], pool[(f + 1 + s) % 3], hold, gap) for f, s, hold, gap in specs
        ]
        async with asyncio.timeout(3600):  # virtual: a missed cycle fails here at once
            outcomes = [await h.wait_done() for h in handles]
        assert repr(robot.resources) == "<ResourceManager idle>"
    for handle, outcome in zip(handles, outcomes, strict=True):
        if outcome is Outcome.FAILED:
            assert isinstance(handle.exception(), ResourceDeadlockError)
        else:
            assert outcome is Outcome.SUCCEEDED
    assert outcomes.count(Outcome.FAILED) == len(refused)


@settings(max_examples=150)
@given(
    st.lists(
        st.tuples(st.integers(0, 2), st.integers(0, 1), st.integers(0, 3), st.integers(0, 3)),
        min_size=2,
        max_size=8,
    )
)
def test_random_nested_locks_finish_or_are_refused_for_a_real_cycle(
    specs: list[tuple[int, int, int, int]],
) -> None:
    run(run_nested, specs)
