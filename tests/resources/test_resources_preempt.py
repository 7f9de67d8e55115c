"""Preemption: the bumper reflex takes the wheels once the preempted action has stopped them."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionInterrupted,
    ActionSkipped,
    ActionState,
    Outcome,
    Robot,
    action,
)
from pyrobots_aio.actions import current_action, lock
from pyrobots_aio.resources import Resource

WHEELS = Resource("wheels")


class Create3(Robot):
    """A robot whose log says who drives the wheels at each step."""

    def __init__(self) -> None:
        super().__init__()
        self.log: list[str] = []

    def note(self, what: str) -> None:
        me = current_action.get()
        holder = self.resources.owner(WHEELS)
        holds = "holds wheels" if holder is not None and holder is me else "no wheels"
        self.log.append(f"{what} ({holds})")


@action
@lock(WHEELS)
async def wander(robot: Create3) -> None:
    robot.note("wander")
    try:
        await asyncio.sleep(3600)
    except ActionCancelled:
        robot.note("wander stopping")
        await asyncio.sleep(0.005)  # cleanup still drives the wheels: brake
        robot.note("wander stopped")
        raise


@action
@lock(WHEELS, priority=10, preempt=True)
async def bumper_reflex(robot: Create3) -> str:
    robot.note("reflex backs off")
    return "backed off"


@pytest.mark.asyncio
async def test_reflex_preempts_and_runs_after_the_cleanup() -> None:
    async with Create3() as robot:
        walk = wander(robot)
        await asyncio.sleep(0)
        reflex = bumper_reflex(robot)
        await asyncio.sleep(0)
        assert reflex.state is ActionState.WAITING
        assert walk.state is ActionState.CANCELLING
        assert robot.resources.owner(WHEELS) is walk
        assert await reflex == "backed off"
        assert robot.log == [
            "wander (holds wheels)",
            "wander stopping (holds wheels)",
            "wander stopped (holds wheels)",
            "reflex backs off (holds wheels)",
        ]
        with pytest.raises(ActionInterrupted) as info:
            await walk  # the main routine gets control back, and carries on
        reason = f"preempted by bumper_reflex#{reflex.id} (priority 10) for 'wheels'"
        assert info.value.reason == reason
        assert info.value.by is reflex
        assert str(info.value) == (
            f"action wander#{walk.id} was cancelled by bumper_reflex#{reflex.id}: {reason}"
        )


@action
async def rest_pose(robot: Create3) -> None:
    async with lock(WHEELS):  # inherited from the preempted parent
        robot.note("rest pose")
        await asyncio.sleep(0)


@action
@lock(WHEELS)
async def safe_wander(robot: Create3) -> None:
    try:
        await asyncio.sleep(3600)
    except ActionCancelled:
        await rest_pose(robot)  # an action started in cleanup runs normally
        robot.note("safe wander stopped")
        raise


@pytest.mark.asyncio
async def test_cleanup_may_start_an_action_that_drives_the_wheels() -> None:
    async with Create3() as robot:
        walk = safe_wander(robot)
        await asyncio.sleep(0)
        reflex = bumper_reflex(robot)
        await reflex
        assert walk.outcome is Outcome.CANCELLED
        assert robot.log == [
            "rest pose (holds wheels)",
            "safe wander stopped (holds wheels)",
            "reflex backs off (holds wheels)",
        ]


@action
async def wander_block(robot: Create3) -> None:
    async with lock(WHEELS):
        try:
            await asyncio.sleep(3600)
        except ActionCancelled:
            await asyncio.sleep(0)
            robot.note("block cleanup")
            raise


@pytest.mark.asyncio
async def test_context_manager_holder_is_preempted_too() -> None:
    async with Create3() as robot:
        walk = wander_block(robot)
        await asyncio.sleep(0)
        await bumper_reflex(robot)
        assert walk.done()
        assert robot.log == ["block cleanup (holds wheels)", "reflex backs off (holds wheels)"]


@action
@lock(WHEELS, priority=10)
async def important(robot: Create3, gate: asyncio.Event) -> None:
    await gate.wait()


@action
@lock(WHEELS, priority=10, preempt=True, wait=False)
async def reflex_or_nothing(robot: Create3) -> None:
    robot.note("reflex")


@pytest.mark.asyncio
async def test_equal_priority_holder_is_not_preempted() -> None:
    gate = asyncio.Event()
    async with Create3() as robot:
        busy = important(robot, gate)
        await asyncio.sleep(0)
        reflex = bumper_reflex(robot)
        skipped = reflex_or_nothing(robot)
        await asyncio.sleep(0)
        assert busy.state is ActionState.RUNNING
        assert reflex.state is ActionState.WAITING
        with pytest.raises(ActionSkipped) as info:
            await skipped
        assert (
            str(info.value) == f"skipped: resource 'wheels' is busy (held by important#{busy.id})"
        )
        gate.set()
        await reflex
        assert busy.outcome is Outcome.SUCCEEDED


@pytest.mark.asyncio
async def test_preempting_request_queues_behind_earlier_waiters_of_its_priority() -> None:
    """DESIGN §4: the reflex still preempts the wanderer, but never overtakes a peer."""
    gate = asyncio.Event()
    async with Create3() as robot:
        walk = wander(robot)
        await asyncio.sleep(0)
        patient = important(robot, gate)
        await asyncio.sleep(0)
        reflex = bumper_reflex(robot)
        await asyncio.sleep(0)
        assert robot.resources.waiters(WHEELS) == [patient, reflex]
        await walk.wait_done()
        assert walk.cancelled()
        await asyncio.sleep(0)
        assert robot.resources.owner(WHEELS) is patient
        assert reflex.state is ActionState.WAITING
        gate.set()
        await patient
        assert await reflex == "backed off"
        assert robot.log[-1] == "reflex backs off (holds wheels)"


@pytest.mark.asyncio
async def test_preempting_without_waiting_takes_over_after_the_cleanup() -> None:
    async with Create3() as robot:
        walk = wander(robot)
        await asyncio.sleep(0)
        reflex = reflex_or_nothing(robot)
        assert await reflex.wait_done() is Outcome.SUCCEEDED
        assert walk.outcome is Outcome.CANCELLED
        assert robot.log == [
            "wander (holds wheels)",
            "wander stopping (holds wheels)",
            "wander stopped (holds wheels)",
            "reflex (holds wheels)",
        ]


@pytest.mark.asyncio
async def test_preempting_without_waiting_is_skipped_by_an_equal_priority_holder() -> None:
    gate = asyncio.Event()
    async with Create3() as robot:
        busy = important(robot, gate)
        await asyncio.sleep(0)
        reflex = reflex_or_nothing(robot)
        assert await reflex.wait_done() is Outcome.SKIPPED
        error = reflex.exception()
        assert isinstance(error, ActionSkipped)
        assert str(error) == f"skipped: resource 'wheels' is busy (held by important#{busy.id})"
        assert busy.state is ActionState.RUNNING
        gate.set()
        await busy
        assert robot.log == []
