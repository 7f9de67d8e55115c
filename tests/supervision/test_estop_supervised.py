"""The emergency stop ends every supervised plan: retry, StateMachine, under a timeout too."""

from __future__ import annotations

import logging
from typing import Any

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionHandle,
    ActionInterrupted,
    EmergencyStopError,
    EventKind,
    Outcome,
    Resource,
    Robot,
    StateMachine,
    action,
    exponential,
    lock,
    retry,
    timeout,
)
from pyrobots_aio.supervision import When, timed_out
from pyrobots_aio.testing import EventLog, FakeBase

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

LEGS = Resource("legs")
S, F, C = Outcome.SUCCEEDED, Outcome.FAILED, Outcome.CANCELLED
REFUSED = (
    "{what} refused: the emergency stop is latched ('operator'); call "
    "robot.clear_emergency_stop() once it is safe to move"
)


class Walker(Robot):
    """The issue's plan: a step that slips, under ``timeout(10)``, retried with a 1 s backoff."""

    def __init__(self) -> None:
        self.record = EventLog()
        super().__init__(instruments=[self.record])
        self.tries: list[float] = []
        self.cleanups: list[float] = []

    @retry(3, backoff=exponential(1, factor=2))
    @timeout(10)
    @action
    @lock(LEGS)
    async def step(self) -> str:
        self.tries.append(self.time())
        await self.sleep(0.5)
        raise RuntimeError("slipped")

    @retry(3, backoff=exponential(1, factor=2))
    @timeout(2)
    @action
    async def think(self) -> str:  # holds no resource: only its retry hands it to the stop
        self.tries.append(self.time())
        try:
            await self.sleep(3600)
        except ActionCancelled:
            await self.sleep(1)  # a cleanup that outlasts the deadline
            self.cleanups.append(self.time())
            raise
        return "thought"


def messages(caplog: pytest.LogCaptureFixture, logger: str) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == logger]


# -- retry --------------------------------------------------------------------------------


async def test_a_stop_during_the_backoff_cancels_the_retry_at_once(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Walker() as robot:
        handle = robot.step()
        await robot.sleep(0.7)  # the first attempt slipped at 0.5; the next is due at 1.5
        with caplog.at_level(logging.WARNING, "pyrobots_aio.robot"):
            stop = robot.emergency_stop("operator")
        with pytest.raises(ActionInterrupted) as stopped:
            await handle
        assert robot.time() == 0.7
        assert (stopped.value.reason, stopped.value.by) == ("emergency stop: operator", stop)
        assert handle.outcome is Outcome.CANCELLED
        await stop
        await robot.sleep(30)
    assert robot.tries == [0.0]  # no further attempt
    assert robot.record.outcomes("step") == ["failed", "cancelled"]
    assert messages(caplog, "pyrobots_aio.robot") == [
        f"emergency stop: operator; preempting step#{handle.id}"
    ]


@pytest.mark.parametrize("name", ["step", "think"])  # holding a resource; holding none
async def test_a_stop_during_an_attempt_cancels_the_retry_and_its_attempt(name: str) -> None:
    async with Walker() as robot:
        handle = getattr(robot, name)()
        await robot.sleep(0.25)
        (attempt,) = handle.children
        stop = robot.emergency_stop("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.cancel_reason == attempt.cancel_reason == "emergency stop: operator"
        error = attempt.exception()
        assert isinstance(error, ActionInterrupted)
        assert error.by is stop
        await stop
        assert stop.outcome is Outcome.SUCCEEDED
        await robot.sleep(30)
    assert robot.tries == [0.0]


async def test_a_timeout_does_not_mask_a_stop() -> None:
    async with Walker() as robot:
        handle = robot.think()
        await robot.sleep(1.5)
        (attempt,) = handle.children
        robot.emergency_stop("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert robot.time() == 2.5  # the cleanup ran past the 2 s deadline
        await robot.sleep(30)
    assert robot.cleanups == [2.5]
    assert robot.tries == [0.0]
    assert attempt.cancel_reason == "emergency stop: operator"
    assert not timed_out(attempt.exception() or ValueError())
    reasons = {e.data["reason"] for e in robot.record.of_kind(EventKind.CANCEL_REQUESTED)}
    assert reasons == {"emergency stop: operator"}


async def test_an_attempts_emergency_stop_error_is_never_retried() -> None:
    tries: list[float] = []

    @retry(5)  # on=Exception
    @action
    async def drive(robot: Robot) -> None:
        tries.append(robot.time())
        raise EmergencyStopError("drive", "operator")  # the stop itself was cleared since

    async with Robot() as robot:
        with pytest.raises(EmergencyStopError) as refused:
            await drive(robot)
        assert str(refused.value) == REFUSED.format(what="drive")
    assert tries == [0.0]


async def test_a_motion_refused_while_latched_is_never_retried() -> None:
    log = EventLog()
    async with FakeBase(instruments=[log]) as robot:
        await robot.emergency_stop("operator")
        with pytest.raises(EmergencyStopError) as refused:
            await retry(3, backoff=exponential(0.1))(robot.drive_distance)(0.5)
        assert str(refused.value) == REFUSED.format(what="drive_distance")
    assert log.outcomes("drive_distance") == ["failed", "failed"]  # one attempt, and the retry


async def test_while_the_stop_is_latched_a_failed_attempt_is_the_last(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Walker() as robot:
        await robot.emergency_stop("operator")  # before the retry starts: its attempts may run
        with caplog.at_level(logging.INFO, "pyrobots_aio.supervision"):
            handle = robot.step()
            with pytest.raises(RuntimeError, match=r"^slipped$"):
                await handle
        assert handle.outcome is Outcome.FAILED
        await robot.sleep(30)
    assert robot.tries == [0.0]
    assert messages(caplog, "pyrobots_aio.supervision") == [
        "step: attempt 1 of 3 failed (RuntimeError('slipped')); not retried: the emergency "
        "stop is latched ('operator')"
    ]


async def test_once_cleared_it_retries_again() -> None:
    async with Walker() as robot:
        await robot.emergency_stop("operator")
        robot.clear_emergency_stop()
        with pytest.raises(RuntimeError, match=r"^slipped$"):
            await robot.step()
    assert robot.tries == [0.0, 1.5, 4.0]


# -- StateMachine ---------------------------------------------------------------------------


class Cell(Robot):
    def __init__(self) -> None:
        super().__init__()
        self.notes: list[tuple[float, str]] = []

    def note(self, what: str) -> None:
        self.notes.append((self.time(), what))

    @action
    async def plan(self) -> None:  # holds no resource: only its machine hands it to the stop
        try:
            await self.sleep(10)
        except ActionCancelled:
            await self.sleep(0.5)
            self.note("plan stopped")
            raise
        self.note("plan done")

    @action
    async def recover(self) -> None:
        self.note("recovering")  # while the stop is latched: the failure path runs
        await self.sleep(1)


def machine(*transitions: tuple[str, str, Outcome | When]) -> StateMachine:
    states: dict[str, Any] = {"plan": Cell.plan, "recover": Cell.recover, "next": Cell.recover}
    return StateMachine("cell", {**states, "done": None}, [*transitions, ("recover", "done", S)])


async def test_a_stop_makes_a_machine_take_its_failure_path() -> None:
    cell = machine(("plan", "done", S), ("plan", "recover", F))
    async with Cell() as robot:
        handle = cell(robot)
        await robot.sleep(2)
        stop = robot.emergency_stop("operator")
        assert await handle == "done"
        assert robot.notes == [(2.5, "plan stopped"), (2.5, "recovering")]
        assert robot.state.cell_history == (
            "plan -> recover: emergency stop: operator",
            "recover -> done: succeeded",
        )
        assert stop.done()  # it waited for the plan's cleanup
        assert robot.emergency_stopped


async def test_the_failure_path_is_taken_whatever_the_cancelled_transitions() -> None:
    cell = machine(("plan", "recover", C))  # for other cancellations, not for a stop
    async with Cell() as robot:
        handle = cell(robot)
        await robot.sleep(2)
        robot.emergency_stop("operator")
        with pytest.raises(EmergencyStopError) as stopped:
            await handle
        assert str(stopped.value) == REFUSED.format(what="StateMachine 'cell' in state 'plan'")
        assert isinstance(stopped.value.__cause__, ActionInterrupted)
        assert handle.outcome is Outcome.FAILED
        assert robot.notes == [(2.5, "plan stopped")]
        assert robot.state.cell_state == "plan"


async def test_a_stop_during_an_event_transitions_cleanup_takes_the_failure_path() -> None:
    cell = machine(("plan", "next", When("skip", becomes=True)), ("plan", "recover", F))
    async with Cell() as robot:
        robot.state.skip = False
        handle = cell(robot)
        await robot.sleep(2)
        robot.state.skip = True  # the plan is cancelled; its cleanup takes 0.5 s
        await robot.sleep(0.25)
        robot.emergency_stop("operator")
        assert await handle == "done"
        assert robot.state.cell_history[0] == "plan -> recover: emergency stop: operator"


async def test_a_machine_stops_handing_over_its_states_once_they_are_done() -> None:
    cell = machine(("plan", "done", S))
    async with Cell() as robot:
        assert await cell(robot) == "done"
        assert robot._estop_callbacks == {}
        await robot.emergency_stop("operator")
        assert robot.notes == [(10.0, "plan done")]


# -- the callbacks --------------------------------------------------------------------------


async def test_a_callback_hands_over_actions_and_the_stop_waits_for_them(
    caplog: pytest.LogCaptureFixture,
) -> None:
    @action
    async def hover(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await robot.sleep(1)  # landing
            raise

    def broken(reason: str) -> list[ActionHandle[Any]]:
        raise RuntimeError(reason)

    async with Robot() as robot:
        drone = hover(robot)
        handing = [drone]
        await robot.sleep(1)

        def hand_over(reason: str) -> list[ActionHandle[Any]]:
            return handing

        robot.add_emergency_stop_callback(broken)
        robot.add_emergency_stop_callback(hand_over)
        robot.add_emergency_stop_callback(hand_over)  # once
        with caplog.at_level(logging.WARNING, "pyrobots_aio.robot"):
            await robot.emergency_stop("operator")
        assert robot.time() == 2.0  # the stop waited for the landing
        assert drone.cancel_reason == "emergency stop: operator"
        failed, stopped = messages(caplog, "pyrobots_aio.robot")
        assert failed.startswith("an emergency stop callback failed (operator): <function ")
        assert stopped == f"emergency stop: operator; preempting hover#{drone.id}"
        robot.remove_emergency_stop_callback(hand_over)
        robot.remove_emergency_stop_callback(hand_over)  # nothing
        handing = [hover(robot)]
        await robot.sleep(1)
        await robot.emergency_stop("again")
        assert not handing[0].done()


async def test_a_callback_that_is_not_callable_is_refused() -> None:
    robot = Robot()
    with pytest.raises(TypeError) as caught:
        robot.add_emergency_stop_callback("stop everything")  # type: ignore[arg-type]
    assert str(caught.value) == (
        "an emergency stop callback must be callable as callback(reason), got 'stop everything'; "
        "pass a function returning the actions to stop"
    )
