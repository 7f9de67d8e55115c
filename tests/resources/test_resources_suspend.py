"""``@lock(..., preempt="suspend")``: a reflex pauses the holder and borrows its resource.

The semantics where DESIGN is silent are in `pyrobots_aio.resources._loans`;
each has a test here, in virtual time.
"""

from __future__ import annotations

from typing import Any

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionHandle,
    ActionSkipped,
    ActionState,
    EventKind,
    Outcome,
    Resource,
    Robot,
    action,
    lock,
)
from pyrobots_aio.actions import current_action
from pyrobots_aio.resources import CompoundResource
from pyrobots_aio.testing import EventLog

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

WHEELS, ARM = Resource("wheels"), Resource("arm")
BODY = CompoundResource(WHEELS, ARM, name="body")


class Log(list[str]):
    def note(self, robot: Robot, what: str) -> None:
        me = current_action.get()
        holder = robot.resources.owner(WHEELS)
        holds = "holds" if holder is not None and holder is me else "not holding"
        self.append(f"{robot.time():g} {what} ({holds})")


def parked(robot: Robot) -> None:
    robot.state.parked = True


def unparked(robot: Robot) -> None:
    robot.state.parked = False


@action(on_pause=parked, on_resume=unparked)
@lock(WHEELS)
async def drive(robot: Robot, log: Log, ticks: int = 4) -> str:
    try:
        for step in range(ticks):
            await robot.sleep(1)
            log.note(robot, f"drive {step + 1}")
    except ActionCancelled:
        log.note(robot, "drive cleanup")
        raise
    return "arrived"


@action
@lock(WHEELS, priority=10, preempt="suspend")
async def reflex(robot: Robot, log: Log, seconds: float = 2) -> str:
    log.note(robot, "reflex starts")
    await robot.sleep(seconds)
    log.note(robot, "reflex ends")
    return "backed off"


@action
@lock(WHEELS, priority=20, preempt="suspend")
async def big_reflex(robot: Robot, log: Log) -> None:
    log.note(robot, "big reflex starts")
    await robot.sleep(1)
    log.note(robot, "big reflex ends")


@action
@lock(WHEELS, priority=5)
async def queued(robot: Robot, log: Log) -> None:
    log.note(robot, "queued runs")


async def test_the_holder_freezes_parks_lends_and_resumes_where_it_stood() -> None:
    log, events = Log(), EventLog()
    async with Robot(instruments=[events]) as robot:
        robot.state.parked = False
        walk = drive(robot, log)
        await robot.sleep(1.5)
        bump = reflex(robot, log)
        await robot.sleep(0)
        assert robot.state.parked is True  # its pause hook ran at once
        assert walk.state is ActionState.PAUSED
        assert walk.pause_reason == f"suspended by reflex#{bump.id} (priority 10) for 'wheels'"
        assert robot.resources.owner(WHEELS) is bump
        assert robot.resources.lenders(WHEELS) == [walk]
        assert repr(robot.resources) == (
            f"<ResourceManager 'wheels' held by reflex#{bump.id} (lent by drive#{walk.id})>"
        )
        assert walk.held == ("wheels",)  # still its own: lent, not lost
        assert await bump == "backed off"
        assert robot.resources.owner(WHEELS) is walk
        assert robot.state.parked is False
        assert robot.resources.lenders(WHEELS) == []
        assert await walk == "arrived"
    assert log == [
        "1 drive 1 (holds)",
        "1.5 reflex starts (holds)",  # at once: nobody's cleanup to wait for
        "3.5 reflex ends (holds)",
        "4 drive 2 (holds)",  # the 1 s sleep did not count the 2 s frozen
        "5 drive 3 (holds)",
        "6 drive 4 (holds)",
    ]
    assert walk.frozen_time() == 2.0
    preempted = events.first(EventKind.RESOURCE_PREEMPTED)
    assert (preempted.action, preempted.data["suspended"]) == (walk.id, True)
    assert events.first(EventKind.ACTION_PAUSED).data["by"] == bump.id
    assert events.outcomes("drive") == ["succeeded"]


async def test_the_holder_gets_it_back_before_anyone_waiting() -> None:
    log = Log()
    async with Robot() as robot:
        walk = drive(robot, log, ticks=2)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 1)
        later = queued(robot, log)  # priority 5 > drive's 0, but drive only lent the wheels
        await robot.sleep(0)
        assert robot.resources.waiters(WHEELS) == [later]
        await bump
        assert robot.resources.owner(WHEELS) is walk
        await later
    assert log == [
        "0.5 reflex starts (holds)",
        "1.5 reflex ends (holds)",
        "2 drive 1 (holds)",
        "3 drive 2 (holds)",
        "3 queued runs (holds)",
    ]


async def nested_suspensions(
    robot: Robot, log: Log
) -> tuple[ActionHandle[str], ActionHandle[str], ActionHandle[None]]:
    """A drive suspended by a reflex at 0.5 s, itself suspended by a bigger one at 1 s."""
    walk = drive(robot, log, ticks=2)
    await robot.sleep(0.5)
    small = reflex(robot, log, 2)
    await robot.sleep(0.5)
    big = big_reflex(robot, log)
    await robot.sleep(0)
    return walk, small, big


async def test_nested_suspensions_give_back_newest_first() -> None:
    log = Log()
    async with Robot() as robot:
        walk, small, big = await nested_suspensions(robot, log)
        assert walk.paused
        assert small.paused
        assert robot.resources.lenders(WHEELS) == [walk, small]
        await big
        assert robot.resources.owner(WHEELS) is small
        assert walk.paused
        assert not small.paused
        await small
        assert await walk == "arrived"
    assert log == [
        "0.5 reflex starts (holds)",
        "1 big reflex starts (holds)",
        "2 big reflex ends (holds)",
        "3.5 reflex ends (holds)",  # 2 s of its own, 1 s frozen
        "4 drive 1 (holds)",
        "5 drive 2 (holds)",
    ]


async def test_a_borrower_cancelled_while_it_lends_onward_keeps_its_lender_suspended() -> None:
    log = Log()
    async with Robot() as robot:
        walk, small, big = await nested_suspensions(robot, log)
        small.cancel("give up")
        assert await small.wait_done() is Outcome.CANCELLED
        # the wheels are still lent onward: walk gets them back when big lets go, not now
        assert robot.resources.held() == {WHEELS: big}
        assert robot.resources.lenders(WHEELS) == [walk]
        assert walk.paused
        await big
        assert robot.resources.held() == {WHEELS: walk}
        assert robot.resources.lenders(WHEELS) == []
        assert not walk.paused
        assert await walk == "arrived"
    assert log == [
        "0.5 reflex starts (holds)",
        "1 big reflex starts (holds)",
        "2 big reflex ends (holds)",
        "2.5 drive 1 (holds)",  # 0.5 s of its first tick left when suspended
        "3.5 drive 2 (holds)",
    ]


async def test_a_holder_cancelled_while_suspended_cleans_up_and_the_queue_is_served() -> None:
    log = Log()
    async with Robot() as robot:
        walk = drive(robot, log)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 2)
        later = queued(robot, log)
        await robot.sleep(0.5)
        walk.cancel("give up")
        assert await walk.wait_done() is Outcome.CANCELLED  # at once: cleanup unfrozen
        assert robot.resources.owner(WHEELS) is bump
        assert robot.resources.lenders(WHEELS) == []
        await bump
        await later
    assert log == [
        "0.5 reflex starts (holds)",
        "1 drive cleanup (not holding)",  # it lent the wheels: its cleanup has them not
        "2.5 reflex ends (holds)",
        "2.5 queued runs (holds)",
    ]


async def test_a_lender_cancelled_during_its_cleanup_forfeits_the_loan() -> None:
    log = Log()

    @action
    @lock(WHEELS)
    async def slow_stop(robot: Robot) -> None:
        try:
            await robot.sleep(60)
        except ActionCancelled:
            await robot.sleep(1.5)  # a long cleanup, past the reflex (within cancel_grace)
            log.note(robot, "slow stop done")
            raise

    async with Robot() as robot:
        walk = slow_stop(robot)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 1)
        later = queued(robot, log)
        await robot.sleep(0.1)
        walk.cancel()
        await bump
        await later  # the wheels went to the queue, not back to the cancelled lender
        await walk.wait_done()
    assert log == [
        "0.5 reflex starts (holds)",
        "1.5 reflex ends (holds)",
        "1.5 queued runs (holds)",
        "2.1 slow stop done (not holding)",
    ]


async def test_a_paused_holder_stays_paused_and_resume_lifts_only_the_pause() -> None:
    log = Log()
    async with Robot() as robot:
        walk = drive(robot, log, ticks=2)
        await robot.sleep(0.5)
        walk.pause("operator")
        bump = reflex(robot, log, 2)
        await robot.sleep(0)
        assert walk.pause_reason == "operator"
        assert walk.resume() is True  # lifts the operator's pause ...
        await robot.sleep(1)
        assert walk.paused  # ... not the suspension
        assert walk.pause_reason == f"suspended by reflex#{bump.id} (priority 10) for 'wheels'"
        walk.pause("operator again")
        await bump
        assert robot.resources.owner(WHEELS) is walk
        await robot.sleep(3)
        assert walk.state is ActionState.PAUSED  # the loan ended, its own pause did not
        assert walk.pause_reason == "operator again"
        walk.resume()
        await walk
    assert log == [
        "0.5 reflex starts (holds)",
        "2.5 reflex ends (holds)",
        "6 drive 1 (holds)",
        "7 drive 2 (holds)",
    ]


async def test_a_borrower_that_never_lets_go_keeps_the_holder_suspended_until_it_ends() -> None:
    log = Log()
    async with Robot() as robot:
        walk = drive(robot, log, ticks=1)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 3600)
        await robot.sleep(600)
        assert walk.paused
        bump.cancel("stuck")
        assert await bump.wait_done() is Outcome.CANCELLED
        assert await walk == "arrived"  # any outcome of the borrower gives back
    assert log == ["0.5 reflex starts (holds)", "601 drive 1 (holds)"]


async def test_no_suspension_of_an_equal_priority_or_cancelling_holder() -> None:
    log = Log()

    @action
    @lock(WHEELS, priority=10)
    async def important(robot: Robot) -> None:
        await robot.sleep(2)

    @action
    @lock(WHEELS, priority=10, preempt="suspend", wait=False)
    async def eager(robot: Robot) -> None:
        log.note(robot, "eager")

    @action
    @lock(WHEELS)
    async def braking(robot: Robot) -> None:
        try:
            await robot.sleep(60)
        except ActionCancelled:
            await robot.sleep(1)  # its cleanup drives the wheels: nobody may suspend it
            log.note(robot, "braked")
            raise

    async with Robot() as robot:
        busy = important(robot)
        await robot.sleep(0.5)
        with pytest.raises(ActionSkipped, match="'wheels' is busy"):
            await eager(robot)
        await busy
        walk = braking(robot)
        await robot.sleep(0.5)
        walk.cancel()
        bump = reflex(robot, log, 1)
        await robot.sleep(0)
        assert bump.state is ActionState.WAITING
        assert not walk.paused
        await bump
    assert log == ["3.5 braked (holds)", "3.5 reflex starts (holds)", "4.5 reflex ends (holds)"]


async def test_a_cancelling_preemptor_cancels_the_lenders_too() -> None:
    log = Log()

    @action
    @lock(WHEELS, priority=50, preempt=True)
    async def stop_all(robot: Robot) -> None:
        log.note(robot, "stop all")

    async with Robot() as robot:
        walk = drive(robot, log)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 5)
        await robot.sleep(0.5)
        await stop_all(robot)
        assert walk.outcome is Outcome.CANCELLED
        assert bump.outcome is Outcome.CANCELLED
    assert log == [
        "0.5 reflex starts (holds)",
        "1 drive cleanup (not holding)",
        "1 stop all (holds)",
    ]


async def test_part_of_a_compound_is_lent_the_rest_stays_held() -> None:
    log = Log()

    @action(on_pause=parked)
    @lock(BODY)
    async def dance(robot: Robot) -> None:
        await robot.sleep(2)
        log.note(robot, "dance ends")

    @action
    @lock(ARM, priority=3)
    async def wave(robot: Robot) -> None:
        log.note(robot, "wave")

    async with Robot() as robot:
        moves = dance(robot)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 1)
        hand = wave(robot)
        await robot.sleep(0)
        assert robot.resources.owner(ARM) is moves  # not lent: still held, frozen
        assert robot.resources.owner(WHEELS) is bump
        await bump
        await hand
        await moves
    assert log == [
        "0.5 reflex starts (holds)",
        "1.5 reflex ends (holds)",
        "3 dance ends (holds)",
        "3 wave (not holding)",
    ]


async def test_the_emergency_stop_cancels_the_lender_and_the_borrower() -> None:
    log = Log()
    async with Robot() as robot:
        walk = drive(robot, log)
        await robot.sleep(0.5)
        bump = reflex(robot, log, 5)
        await robot.sleep(0.5)
        await robot.emergency_stop("cliff")
        assert (walk.outcome, bump.outcome) == (Outcome.CANCELLED, Outcome.CANCELLED)
        assert repr(robot.resources) == "<ResourceManager idle>"


@pytest.mark.parametrize("bad", ["Suspend", 1, None])
async def test_a_bad_preempt_is_refused_naming_it(bad: Any) -> None:
    with pytest.raises(Exception, match=r"preempt must be True, False or 'suspend', got "):
        lock(WHEELS, preempt=bad)
