"""timeout: the action ends CANCELLED with "timeout after N s", its cleanup run."""

from __future__ import annotations

import math
import re

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionInterrupted,
    EventKind,
    Outcome,
    Resource,
    Robot,
    action,
    lock,
    timeout,
)
from pyrobots_aio.supervision import TimeoutReason, timed_out
from pyrobots_aio.testing import EventLog

ARM = Resource("arm")


class Waver(Robot):
    def __init__(self) -> None:
        self.record = EventLog()
        super().__init__(instruments=[self.record])
        self.notes: list[tuple[float, str]] = []

    @timeout(2)
    @action
    @lock(ARM)
    async def wave(self, seconds: float) -> str:
        try:
            await self.sleep(seconds)
        except ActionCancelled:
            await self.sleep(0.5)
            self.notes.append((self.time(), "arm lowered"))
            raise
        return "waved"


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_it_cancels_the_action_itself_and_its_cleanup_runs() -> None:
    async with Waver() as robot:
        handle = robot.wave(60)
        with pytest.raises(ActionInterrupted) as stop:
            await handle
        assert robot.time() == 2.5
    assert handle.outcome is Outcome.CANCELLED
    assert stop.value.reason == "timeout after 2 s"
    assert isinstance(stop.value.reason, TimeoutReason)
    assert stop.value.reason.seconds == 2.0
    assert stop.value.by is None
    assert timed_out(stop.value)
    assert str(stop.value) == f"action wave#{handle.id} was cancelled: timeout after 2 s"
    assert robot.notes == [(2.5, "arm lowered")]
    (cancel,) = robot.record.of_kind(EventKind.CANCEL_REQUESTED, "wave")
    assert (cancel.time, cancel.data["reason"], cancel.data["by"]) == (
        2.0,
        "timeout after 2 s",
        None,
    )
    # the lock below the timeout still held the arm until the cleanup was over
    released = robot.record.first(EventKind.RESOURCE_RELEASED, "wave")
    assert released.time == 2.5


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_action_done_in_time_is_untouched_and_its_timer_is_gone() -> None:
    async with Waver() as robot:
        assert await robot.wave(1.5) == "waved"
        await robot.sleep(10)
        assert robot.record.of_kind(EventKind.CANCEL_REQUESTED) == []


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_deadline_counts_the_wait_for_a_resource() -> None:
    async with Waver() as robot:
        first = robot.wave(1.5)
        second = robot.wave(1.5)  # waits 1.5 s for the arm, then needs 1.5 s more
        assert await first == "waved"
        assert await second.wait_done() is Outcome.CANCELLED
        assert second.cancel_reason == "timeout after 2 s"


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_another_cancellation_keeps_its_own_reason() -> None:
    async with Waver() as robot:
        handle = robot.wave(60)
        await robot.sleep(1)
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.cancel_reason == "operator"
        assert not timed_out(handle.exception() or ValueError())


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_call_form_and_fractions_of_a_second() -> None:
    @action
    async def look(robot: Robot) -> None:
        await robot.sleep(1)

    async with Robot() as robot:
        with pytest.raises(ActionInterrupted, match=r"was cancelled: timeout after 0\.25 s$"):
            await timeout(0.25)(look)(robot)
        assert robot.time() == 0.25


@pytest.mark.parametrize("seconds", [0, -1, math.inf, math.nan, True, "2"])
def test_bad_deadlines_are_refused(seconds: object) -> None:
    hint = " (a bool is not a number)" if seconds is True else ""
    message = f"timeout must be a positive number of seconds, got {seconds!r}{hint}"
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        timeout(seconds)  # type: ignore[arg-type]
