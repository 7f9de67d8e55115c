"""Many contending actions: no deadlock, mutual exclusion always, nothing leaked.

The random programs mix waiting, cancelling and suspending (``preempt="suspend"``)
requests: a lender is frozen while its resource is lent, and any body that
runs holds what it locked.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import Any, Literal

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from pyrobots_aio import ActionHandle, Outcome, Robot, action
from pyrobots_aio.actions import current_action, lock
from pyrobots_aio.resources import (
    CompoundResource,
    Resource,
    ResourceManager,
    _grant,
    _loans,
    _rules,
)

A, B, C = Resource("a"), Resource("b"), Resource("c")
AB, BA = CompoundResource(A, B, name="ab"), CompoundResource(B, A, name="ba")


class Exclusion:
    """Who uses each plain resource right now; fails on two unrelated users at once."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.users: dict[Resource, list[ActionHandle[Any]]] = {}
        self.entries = 0

    def enter(self, leaves: tuple[Resource, ...]) -> ActionHandle[Any]:
        me = current_action.get()
        assert me is not None
        for leaf in leaves:
            users = self.users.setdefault(leaf, [])
            assert all(me.childof(user) or self.idle_user(user, leaf) for user in users), (
                leaf,
                users,
                me,
            )
            assert self.robot.resources.owner(leaf) is me
            users.append(me)
        self.entries += 1
        return me

    def idle_user(self, user: ActionHandle[Any], leaf: Resource) -> bool:
        """A user that lent ``leaf`` (preempt="suspend"): frozen, or cancelled and forfeiting."""
        return user.paused or (user.cancel_requested and not self.holds(user, leaf))

    def holds(self, me: ActionHandle[Any], leaf: Resource) -> bool:
        owner = self.robot.resources.owner(leaf)
        return owner is not None and (owner is me or owner.childof(me))

    def check_held(self, me: ActionHandle[Any], leaves: tuple[Resource, ...]) -> None:
        """A body that runs holds its resources (a lender runs again only once given back)."""
        for leaf in leaves:
            assert self.holds(me, leaf), (leaf, me, self.robot.resources)

    def leave(self, me: ActionHandle[Any], leaves: tuple[Resource, ...]) -> None:
        for leaf in leaves:
            self.users[leaf].remove(me)

    def idle(self) -> bool:
        return not any(self.users.values())


@action
@lock(A)
@lock(B)
async def ab_stacked(robot: Robot, ex: Exclusion) -> None:
    me = ex.enter((A, B))
    await asyncio.sleep(0)
    ex.leave(me, (A, B))


@action
@lock(B)
@lock(A)
async def ba_stacked(robot: Robot, ex: Exclusion) -> None:
    me = ex.enter((B, A))
    await asyncio.sleep(0)
    ex.leave(me, (B, A))


@action
async def in_block(robot: Robot, ex: Exclusion, resource: Resource | CompoundResource) -> None:
    async with lock(resource):
        me = ex.enter(resource.leaves)
        try:
            await asyncio.sleep(0)
        finally:
            ex.leave(me, resource.leaves)


@pytest.mark.asyncio
async def test_opposite_order_compounds_in_a_thousand_concurrent_trials() -> None:
    async with Robot() as robot:
        ex = Exclusion(robot)
        handles: list[ActionHandle[Any]] = []
        for i in range(1000):
            mine = (Resource(f"p{i}"), Resource(f"q{i}"))
            handles += [
                ab_stacked(robot, ex),
                ba_stacked(robot, ex),
                in_block(robot, ex, AB if i % 2 else BA),
                in_block(robot, ex, CompoundResource(*mine, name=f"pq{i}")),
                in_block(robot, ex, CompoundResource(*reversed(mine), name=f"qp{i}")),
                in_block(robot, ex, (A, B, mine[0])[i % 3]),
            ]
        async with asyncio.timeout(60):  # a deadlock fails here instead of hanging
            outcomes = [await h.wait_done() for h in handles]
        assert outcomes == [Outcome.SUCCEEDED] * 6000
        assert ex.entries == 6000
        assert ex.idle()
        assert repr(robot.resources) == "<ResourceManager idle>"


# -- property: random lock / cancel / preempt programs --------------------------

RESOURCES = (A, B, C, AB, CompoundResource(B, C, name="bc"), CompoundResource(A, B, C, name="abc"))


@dataclass(frozen=True)
class Spawn:
    resource: int
    priority: int
    wait: bool
    preempt: bool | Literal["suspend"]
    ticks: int
    block: bool
    child: bool


@dataclass(frozen=True)
class Cancel:
    which: int


@dataclass(frozen=True)
class Tick:
    ticks: int


OPS = st.one_of(
    st.builds(
        Spawn,
        resource=st.integers(0, len(RESOURCES) - 1),
        priority=st.integers(0, 2),
        wait=st.booleans(),
        preempt=st.sampled_from([False, True, "suspend"]),
        ticks=st.integers(0, 3),
        block=st.booleans(),
        child=st.booleans(),
    ),
    st.builds(Cancel, which=st.integers(0, 40)),
    st.builds(Tick, ticks=st.integers(1, 4)),
)


async def use(ex: Exclusion, leaves: tuple[Resource, ...], spec: Spawn) -> None:
    me = ex.enter(leaves)
    try:
        for _ in range(spec.ticks):
            await asyncio.sleep(0)
            ex.check_held(me, leaves)
        if spec.child:  # a child takes part of what its parent holds
            await in_block(ex.robot, ex, leaves[-1])
    finally:
        try:
            await asyncio.sleep(0)  # cleanup still uses the resources
        finally:
            ex.leave(me, leaves)


async def locked_body(robot: Robot, ex: Exclusion, spec: Spawn) -> None:
    await use(ex, RESOURCES[spec.resource].leaves, spec)


async def block_body(robot: Robot, ex: Exclusion, spec: Spawn) -> None:
    resource = RESOURCES[spec.resource]
    async with lock(resource, spec.wait, spec.priority, spec.preempt):
        await use(ex, resource.leaves, spec)


def spawn(robot: Robot, ex: Exclusion, spec: Spawn) -> ActionHandle[None]:
    if spec.block:
        return action(block_body)(robot, ex, spec)
    options = (spec.wait, spec.priority, spec.preempt)
    return action(lock(RESOURCES[spec.resource], *options)(locked_body))(robot, ex, spec)


def check_consistent(manager: ResourceManager[ActionHandle[Any]]) -> None:
    """Holds form chains of descendants; no waiting request could proceed (no lost wake-up)."""
    for leaf in manager._leaves.values():
        for outer, inner in zip(leaf.holds, leaf.holds[1:], strict=False):
            assert inner.owner is outer.owner or inner.owner.childof(outer.owner)
        for grant in leaf.queue:
            assert grant.waiting
            assert not _rules.grantable(grant, manager._below), grant
            assert grant.preempt != "suspend" or _loans.plan(grant) is None, grant
        holders = [h.owner for h in leaf.holds] + [h.owner for x in leaf.lent for h in x.holds]
        for loan in leaf.lent:  # an emptied loan stays while its borrower holds the leaf
            assert loan.holds or any(_grant.descends(h, loan.borrower.owner) for h in holders), loan
            assert not loan.holds or loan.lender.paused or loan.lender.cancel_requested, loan


async def run_program(ops: list[Spawn | Cancel | Tick]) -> None:
    robot = Robot()
    handles: list[ActionHandle[None]] = []
    async with robot:
        ex = Exclusion(robot)
        for op in ops:
            if isinstance(op, Spawn):
                handles.append(spawn(robot, ex, op))
            elif isinstance(op, Cancel) and handles:
                handles[op.which % len(handles)].cancel("random cancel")
            for _ in range(op.ticks if isinstance(op, Tick) else 1):
                await asyncio.sleep(0)
            check_consistent(robot.resources)
        if handles:
            async with asyncio.timeout(10):
                await asyncio.wait(handles)  # handles work with asyncio.wait
        assert ex.idle()
        manager = robot.resources
        assert repr(manager) == "<ResourceManager idle>"
        assert manager._below == {}
        assert manager._owners == {}
        assert manager._loans.count == {}
    assert all(h.outcome is not Outcome.FAILED for h in handles), [h.exception() for h in handles]
    left = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
    assert not left


@settings(max_examples=300)
@given(st.lists(OPS, min_size=1, max_size=30))
@example(  # a borrower lending onward cancelled: its lender got the leaf back too early
    [
        Spawn(resource=0, priority=0, wait=False, preempt=False, ticks=0, block=False, child=True),
        Spawn(
            resource=0, priority=1, wait=False, preempt="suspend", ticks=1, block=False, child=False
        ),
        Spawn(
            resource=0, priority=2, wait=False, preempt="suspend", ticks=0, block=False, child=True
        ),
        Cancel(which=1),
    ]
)
def test_random_lock_cancel_preempt_programs_keep_exclusion_and_leak_nothing(
    ops: list[Spawn | Cancel | Tick],
) -> None:
    asyncio.run(run_program(ops))
