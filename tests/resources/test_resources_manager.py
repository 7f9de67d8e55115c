"""The ResourceManager on its own, with plain owner objects standing in for actions."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import (
    ActionSkipped,
    EventKind,
    ExecEvent,
    InvalidResourceError,
    LockUsageError,
)
from pyrobots_aio._core._instrument import Instruments
from pyrobots_aio.resources import CompoundResource, Grant, Resource, ResourceManager, _rules

if TYPE_CHECKING:
    from collections.abc import Callable

W, X, Y = Resource("w"), Resource("x"), Resource("y")
XY = CompoundResource(X, Y, name="xy")


class Owner:
    """A stand-in for an ActionHandle: what the manager needs (`Owner`), and a record of cancels."""

    count = 0

    def __init__(self, name: str, parent: Owner | None = None) -> None:
        Owner.count += 1
        self.id = Owner.count
        self.name = name
        self.parent = parent
        self.reasons: list[str | None] = []
        self.cancel_requested = False
        self._done = False
        self._callbacks: list[Callable[[], None]] = []

    def cancel(self, reason: str | None = None) -> bool:
        if self._done:
            return False
        self.reasons.append(reason)
        self.cancel_requested = True
        return True

    def done(self) -> bool:
        return self._done

    def add_finalizer(self, finalizer: Callable[[], None]) -> None:
        self._callbacks.append(finalizer)

    def finish(self) -> None:
        for finalizer in self._callbacks:
            finalizer()
        self._done = True

    def __repr__(self) -> str:
        return f"<Owner {self.name}#{self.id}>"


Manager = ResourceManager[Owner]


def start(
    manager: Manager, owner: Owner, *resources: Resource | CompoundResource, **options: object
) -> asyncio.Task[Grant[Owner]]:
    return asyncio.create_task(manager.acquire(owner, *resources, **options))  # type: ignore[arg-type]


async def settle() -> None:
    for _ in range(3):
        await asyncio.sleep(0)


def assert_idle(manager: Manager) -> None:
    assert repr(manager) == "<ResourceManager idle>"
    assert manager.held() == {}
    assert manager._below == {}


@pytest.mark.asyncio
async def test_free_resource_is_granted_without_waiting() -> None:
    manager = Manager()
    a = Owner("a")
    grant = await manager.acquire(a, XY)
    assert grant.held
    assert manager.held_by(a) == ("xy",)
    assert manager.holdings(a) == (("xy",), ())  # held and awaited, in one question
    assert manager.owner(X) is a
    assert manager.owner(XY) is a
    assert manager.owner(W) is None
    assert manager.held() == {X: a, Y: a}
    assert repr(grant) == f"<Grant 'xy' held by a#{a.id} priority=0>"
    grant.release()
    grant.release()  # idempotent
    assert manager.held_by(a) == ()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_waiters_are_served_by_priority_then_in_order() -> None:
    manager = Manager()
    holder = Owner("holder")
    grant = await manager.acquire(holder, W)
    owners = [Owner(f"p{p}") for p in (0, 5, 1, 5)]
    tasks = [start(manager, o, W, priority=p) for o, p in zip(owners, (0, 5, 1, 5), strict=True)]
    await settle()
    expected = [owners[1], owners[3], owners[2], owners[0]]
    assert manager.waiters(W) == expected
    assert all(manager.awaited_by(o) == ("w",) for o in owners)
    assert manager.holdings(owners[0]) == ((), ("w",))
    served = []
    grant.release()
    for _ in expected:
        await settle()
        now = manager.owner(W)
        assert now is not None
        served.append(now)
        done = next(t for t, o in zip(tasks, owners, strict=True) if o is now)
        (await done).release()
    assert served == expected
    assert_idle(manager)


@pytest.mark.asyncio
async def test_compound_request_is_not_starved_by_single_requests() -> None:
    manager = Manager()
    x_holder, compound = Owner("x_holder"), Owner("compound")
    x_grant = await manager.acquire(x_holder, X)
    compound_task = start(manager, compound, XY)
    await settle()
    # Held up by x_holder, the compound request cannot run anyway: single requests
    # use Y meanwhile instead of leaving it idle, BYPASS_LIMIT of them ...
    await pass_by(manager, Y)
    # ... then it keeps its place.
    singles = [Owner(f"y{i}") for i in range(5)]
    y_tasks = [start(manager, o, Y) for o in singles]
    await settle()
    assert manager.owner(Y) is None  # free, but promised to the compound request
    assert manager.waiters(Y) == [compound, *singles]
    with pytest.raises(ActionSkipped) as info:
        await manager.acquire(Owner("impatient"), Y, wait=False)
    assert str(info.value) == (
        f"skipped: resource 'y' is promised to compound#{compound.id} (queued ahead, priority 0)"
    )
    assert info.value.holder is None
    assert info.value.queued is compound
    assert info.value.queued_priority == 0
    x_grant.release()
    await settle()
    assert manager.owner(XY) is compound
    (await compound_task).release()
    for task, owner in zip(y_tasks, singles, strict=True):
        await settle()
        assert manager.owner(Y) is owner
        (await task).release()
    assert_idle(manager)


async def pass_by(manager: Manager, resource: Resource) -> None:
    """Pass the held-up requests queued for ``resource`` as often as they may be passed."""
    for _ in range(_rules.BYPASS_LIMIT):
        (await manager.acquire(Owner("passer"), resource)).release()


@pytest.mark.asyncio
async def test_higher_priority_single_request_may_pass_a_waiting_compound() -> None:
    manager = Manager()
    x_grant = await manager.acquire(Owner("x_holder"), X)
    compound_task = start(manager, Owner("compound"), XY, priority=0)
    await settle()
    urgent = Owner("urgent")
    grant = await manager.acquire(urgent, Y, priority=1)
    assert manager.owner(Y) is urgent
    grant.release()
    x_grant.release()
    (await compound_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_skip_names_the_busy_resource_and_its_holder() -> None:
    manager = Manager()
    holder = Owner("lift_box")
    grant = await manager.acquire(holder, XY)
    with pytest.raises(ActionSkipped) as info:
        await manager.acquire(Owner("scratch_head"), W, Y, wait=False)
    assert str(info.value) == f"skipped: resource 'y' is busy (held by lift_box#{holder.id})"
    assert info.value.resource == Y
    assert info.value.holder is holder
    grant.release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_descendant_takes_what_its_ancestor_holds_even_with_others_waiting() -> None:
    manager = Manager()
    parent = Owner("parent")
    child = Owner("child", parent)
    grandchild = Owner("grandchild", child)
    parent_grant = await manager.acquire(parent, XY)
    stranger_task = start(manager, Owner("stranger"), X)
    await settle()
    child_grant = await manager.acquire(child, X)  # no wait: inherited
    assert manager.owner(X) is child
    assert manager.owner(Y) is parent
    deep = await manager.acquire(grandchild, XY)
    assert manager.owner(XY) is grandchild
    deep.release()
    child_grant.release()
    assert manager.owner(X) is parent
    parent_grant.release()
    await settle()
    assert manager.owner(X) is not None
    assert manager.owner(X) is not parent
    (await stranger_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_siblings_exclude_each_other_under_an_inherited_resource() -> None:
    manager = Manager()
    parent = Owner("parent")
    first, second = Owner("first", parent), Owner("second", parent)
    parent_grant = await manager.acquire(parent, W)
    first_grant = await manager.acquire(first, W)
    second_task = start(manager, second, W)
    await settle()
    assert manager.waiters(W) == [second]
    first_grant.release()
    await settle()
    assert manager.owner(W) is second
    (await second_task).release()
    parent_grant.release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_parent_releasing_first_leaves_the_child_holding() -> None:
    manager = Manager()
    parent = Owner("parent")
    child = Owner("child", parent)
    parent_grant = await manager.acquire(parent, W)
    child_grant = await manager.acquire(child, W)
    stranger_task = start(manager, Owner("stranger"), W)
    await settle()
    parent_grant.release()
    await settle()
    assert manager.owner(W) is child
    assert not stranger_task.done()
    child_grant.release()
    (await stranger_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_holder_taking_more_does_not_yield_to_a_request_it_blocks() -> None:
    """Holding w, then asking for x while a request for w+x waits: no self-deadlock."""
    manager = Manager()
    holder = Owner("holder")
    w_grant = await manager.acquire(holder, W)
    waiting = start(manager, Owner("both"), W, X)
    await settle()
    x_grant = await manager.acquire(holder, X)
    assert manager.held_by(holder) == ("w", "x")
    x_grant.release()
    w_grant.release()
    (await waiting).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_child_is_served_once_its_parent_blocks_the_request_ahead() -> None:
    """A request the child yields to becomes blocked by the child's parent: the child goes."""
    manager = Manager()
    w_holder = Owner("w_holder")
    parent = Owner("parent")
    child = Owner("child", parent)
    w_grant = await manager.acquire(w_holder, W)
    big_task = start(manager, Owner("big"), W, X, Y)
    await settle()
    await pass_by(manager, Y)  # then the child yields to it
    child_task = start(manager, child, Y)
    await settle()
    assert manager.waiters(Y) == [manager.waiters(W)[0], child]
    x_grant = await manager.acquire(parent, X, priority=1)
    await settle()
    assert child_task.done()
    assert manager.owner(Y) is child
    (await child_task).release()
    x_grant.release()
    w_grant.release()
    (await big_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_preemption_cancels_lower_priority_holders_but_never_overtakes_a_peer() -> None:
    """DESIGN §4: nobody overtakes an earlier queued request of equal or higher priority."""
    manager = Manager()
    driver = Owner("drive")
    grant = await manager.acquire(driver, W, priority=0)
    queued = Owner("queued")
    queued_task = start(manager, queued, W, priority=10)
    await settle()
    reflex = Owner("bumper_reflex")
    reflex_task = start(manager, reflex, W, priority=10, preempt=True)
    await settle()
    assert driver.reasons == [f"preempted by bumper_reflex#{reflex.id} (priority 10) for 'w'"]
    assert manager.owner(W) is driver  # until its cleanup is over
    assert manager.waiters(W) == [queued, reflex]
    grant.release()
    await settle()
    assert manager.owner(W) is queued
    (await queued_task).release()
    await settle()
    assert manager.owner(W) is reflex
    (await reflex_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_preempting_request_that_will_not_wait_cancels_nobody_behind_a_peer() -> None:
    """Cancelling the holder would only serve the earlier peer: skipped, naming both."""
    recorder = Recorder()
    instruments = Instruments()
    instruments.add(recorder)
    manager = Manager(instruments, clock=lambda: 0.0)
    low, patient = Owner("low"), Owner("patient")
    grant = await manager.acquire(low, W, priority=0)
    patient_task = start(manager, patient, W, priority=5)
    await settle()
    reflex_task = start(manager, Owner("reflex"), W, priority=5, preempt=True, wait=False)
    await settle()
    assert low.reasons == []
    with pytest.raises(ActionSkipped) as info:
        reflex_task.result()  # done at once, never waiting
    assert str(info.value) == (
        f"skipped: resource 'w' is busy (held by low#{low.id}) and promised to "
        f"patient#{patient.id} (queued ahead, priority 5)"
    )
    assert (info.value.holder, info.value.queued, info.value.queued_priority) == (low, patient, 5)
    skip = recorder.events[-1]
    assert (skip.kind, skip.name) == (EventKind.RESOURCE_SKIPPED, "reflex")
    assert dict(skip.data) == {
        "resources": ["w"],
        "leaves": ["w"],
        "priority": 5,
        "busy": "w",
        "holder": low.id,
        "queued": patient.id,
    }
    grant.release()
    (await patient_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_no_preemption_of_an_equal_priority_holder() -> None:
    manager = Manager()
    holder = Owner("holder")
    grant = await manager.acquire(holder, W, priority=5)
    with pytest.raises(ActionSkipped):
        await manager.acquire(Owner("rival"), W, priority=5, preempt=True, wait=False)
    rival_task = start(manager, Owner("rival"), W, priority=5, preempt=True)
    await settle()
    assert holder.reasons == []
    assert not rival_task.done()
    grant.release()
    (await rival_task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_preemption_needs_every_holder_in_the_way_lower() -> None:
    manager = Manager()
    low, high = Owner("low"), Owner("high")
    low_grant = await manager.acquire(low, X, priority=0)
    high_grant = await manager.acquire(high, Y, priority=20)
    task = start(manager, Owner("mid"), XY, priority=10, preempt=True)
    await settle()
    assert low.reasons == []
    assert high.reasons == []
    low_grant.release()
    high_grant.release()
    (await task).release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_cancel_while_waiting_leaves_nothing_queued_and_unblocks_those_behind() -> None:
    manager = Manager()
    x_grant = await manager.acquire(Owner("x_holder"), X)
    compound = Owner("compound")
    compound_task = start(manager, compound, XY)
    await settle()
    await pass_by(manager, Y)
    single = Owner("single")
    single_task = start(manager, single, Y)
    await settle()
    assert not single_task.done()  # behind the compound request
    compound_task.cancel()
    await settle()
    assert compound_task.cancelled()
    assert manager.awaited_by(compound) == ()
    assert manager.waiters(XY) == []
    assert manager.owner(Y) is single
    (await single_task).release()
    x_grant.release()
    assert_idle(manager)


@pytest.mark.asyncio
async def test_cancelled_after_being_granted_still_releases() -> None:
    manager = Manager()
    holder = await manager.acquire(Owner("holder"), W)
    task = start(manager, Owner("next"), W)
    await settle()
    holder.release()  # grants W to the waiter, whose task has not resumed yet
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert_idle(manager)


@pytest.mark.asyncio
async def test_owner_done_releases_what_it_still_holds(caplog: pytest.LogCaptureFixture) -> None:
    manager = Manager()
    forgetful = Owner("forgetful")
    await manager.acquire(forgetful, W)
    waiting_task = start(manager, forgetful, X, Y)
    other = await manager.acquire(Owner("other"), Y)
    await settle()
    forgetful.finish()
    assert manager.held_by(forgetful) == ()
    assert manager.awaited_by(forgetful) == ()
    with pytest.raises(LockUsageError) as info:
        await waiting_task
    assert (
        str(info.value) == f"forgetful#{forgetful.id} finished while still waiting for ['x', 'y']"
    )
    assert [r.getMessage() for r in caplog.records] == [
        f"forgetful#{forgetful.id} is done but still held ['w']; released"
    ]
    other.release()
    assert_idle(manager)
    with pytest.raises(LockUsageError) as info:
        await manager.acquire(forgetful, W)
    assert str(info.value) == f"forgetful#{forgetful.id} is done; it cannot take ['w'] any more"


@pytest.mark.asyncio
async def test_bad_requests_are_rejected_with_the_fix() -> None:
    manager = Manager()
    a = Owner("a")
    with pytest.raises(InvalidResourceError) as info:
        await manager.acquire(a, "w")  # type: ignore[arg-type]
    assert str(info.value) == (
        "'w' is not a resource (needed as a resource to acquire); "
        "declare it as Resource('w') or CompoundResource(...)"
    )
    with pytest.raises(LockUsageError) as error:
        await manager.acquire(a, W, priority="high")  # type: ignore[arg-type]
    assert str(error.value) == (
        "priority must be an int, got 'high'; e.g. priority=10 (higher goes first)"
    )
    with pytest.raises(LockUsageError, match=r"^priority must be an int, got True;"):
        await manager.acquire(a, W, priority=True)
    with pytest.raises(LockUsageError, match=r"^wait must be True or False, got 0$"):
        await manager.acquire(a, W, wait=0)  # type: ignore[arg-type]
    with pytest.raises(LockUsageError) as error:
        await manager.acquire(a)
    assert str(error.value) == f"a#{a.id} asked for no resource; name at least one to acquire"
    with pytest.raises(InvalidResourceError):
        manager.owner("w")  # type: ignore[arg-type]
    assert_idle(manager)


@pytest.mark.asyncio
async def test_repr_shows_holders_and_waiters() -> None:
    manager = Manager()
    holder = Owner("lift_box")
    grant = await manager.acquire(holder, XY)
    waiters = [Owner(f"w{i}") for i in range(7)]
    tasks = [start(manager, o, X) for o in waiters]
    await settle()
    names = ", ".join(f"w{i}#{o.id}" for i, o in enumerate(waiters[:5]))
    assert repr(manager) == (
        f"<ResourceManager 'x' held by lift_box#{holder.id}, waiters [{names} and 2 more]; "
        f"'y' held by lift_box#{holder.id}>"
    )
    assert repr(grant) == f"<Grant 'xy' held by lift_box#{holder.id} priority=0>"
    for task in tasks:
        task.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    grant.release()
    assert_idle(manager)


class Recorder:
    def __init__(self) -> None:
        self.events: list[ExecEvent] = []

    def on_event(self, event: ExecEvent) -> None:
        self.events.append(event)


@pytest.mark.asyncio
async def test_every_arbitration_step_is_instrumented() -> None:
    recorder = Recorder()
    instruments = Instruments()
    instruments.add(recorder)
    ticks = iter(range(100))
    manager = Manager(instruments, clock=lambda: float(next(ticks)))
    low, reflex = Owner("low"), Owner("reflex")
    grant = await manager.acquire(low, XY)
    with pytest.raises(ActionSkipped):
        await manager.acquire(Owner("skipper"), X, wait=False)
    task = start(manager, reflex, X, priority=3, preempt=True)
    await settle()
    grant.release()
    (await task).release()
    got = [(e.kind, e.time, e.name, dict(e.data)) for e in recorder.events]
    common = {"resources": ["xy"], "leaves": ["x", "y"], "priority": 0}
    mine = {"resources": ["x"], "leaves": ["x"]}
    reason = f"preempted by reflex#{reflex.id} (priority 3) for 'x'"
    skipped = {**mine, "busy": "x", "holder": low.id, "queued": None, "priority": 0}
    preempted = {**common, "resource": "x", "by": reflex.id, "reason": reason}
    assert got == [
        (EventKind.RESOURCE_ACQUIRED, 0.0, "low", common),
        (EventKind.RESOURCE_SKIPPED, 1.0, "skipper", skipped),
        (EventKind.RESOURCE_PREEMPTED, 2.0, "low", preempted),
        (EventKind.RESOURCE_WAITING, 3.0, "reflex", {**mine, "priority": 3}),
        (EventKind.RESOURCE_RELEASED, 4.0, "low", common),
        (EventKind.RESOURCE_ACQUIRED, 5.0, "reflex", {**mine, "priority": 3}),
        (EventKind.RESOURCE_RELEASED, 6.0, "reflex", {**mine, "priority": 3}),
    ]
    assert all(e.action is not None for e in recorder.events)


@pytest.mark.asyncio
async def test_draining_a_long_line_serves_everyone_in_order() -> None:
    manager = Manager()
    first = await manager.acquire(Owner("first"), W)
    order: list[int] = []

    async def worker(i: int) -> None:
        grant = await manager.acquire(Owner(f"w{i}"), W)
        order.append(i)
        grant.release()

    tasks = [asyncio.create_task(worker(i)) for i in range(1000)]
    await settle()
    assert len(manager.waiters(W)) == 1000
    first.release()
    await asyncio.gather(*tasks)
    assert order == list(range(1000))
    assert_idle(manager)
