"""Failures: reported when nobody retrieves them, not when somebody does; finishing-phase cancel."""

from __future__ import annotations

import logging
import traceback

import pytest

from pyrobots_aio import ActionCancelled, ActionInterrupted, Outcome, Robot, action
from pyrobots_aio.actions import current_action

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

UNRETRIEVED = "failed and nobody is waiting for it"


@action
async def boom(robot: Robot, after: float) -> None:
    await robot.sleep(after)
    raise RuntimeError("servo unplugged")


@action
async def quick(robot: Robot) -> str:
    await robot.sleep(1.0)
    return "done"


@action
async def boom_knowing_itself(robot: Robot) -> None:
    me = current_action.get()  # a local referring to its own handle, kept by the traceback
    await robot.sleep(0.1)
    raise RuntimeError(f"{me!r} broke")


def _reports(caplog: pytest.LogCaptureFixture) -> list[logging.LogRecord]:
    return [r for r in caplog.records if UNRETRIEVED in r.getMessage()]


async def test_a_failure_retrieved_later_is_never_reported(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        first, second = quick(robot), boom(robot, 0.1)
        assert await first == "done"  # meanwhile the second failed, with nobody waiting yet
        with pytest.raises(RuntimeError, match="servo unplugged"):
            await second
        del first, second
    assert _reports(caplog) == []


async def test_a_forgotten_failure_is_reported_when_its_handle_goes(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        handle = boom(robot, 0.1)
        await robot.sleep(1.0)
        assert handle.done()
        assert _reports(caplog) == []  # somebody may still retrieve it
        del handle  # ... now nobody can: reported at once, no garbage collection needed
        (record,) = _reports(caplog)
    assert record.getMessage() == f"action boom#1 {UNRETRIEVED}"
    assert record.levelno == logging.ERROR
    assert record.exc_info is not None
    error = record.exc_info[1]
    assert isinstance(error, RuntimeError)
    frames = traceback.extract_tb(error.__traceback__)
    assert [f.name for f in frames] == ["boom"]  # starts in the action's own code
    assert frames[0].line == 'raise RuntimeError("servo unplugged")'


async def test_a_failure_whose_frame_refers_to_its_own_handle_is_still_reported(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        boom_knowing_itself(robot)
        await robot.sleep(1.0)
        assert [r.getMessage() for r in _reports(caplog)] == [
            f"action boom_knowing_itself#1 {UNRETRIEVED}"
        ]


async def test_exception_and_wait_done_retrieve_the_failure(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        checked, observed = boom(robot, 0.1), boom(robot, 0.1)
        await robot.sleep(1.0)
        assert isinstance(checked.exception(), RuntimeError)
        assert await observed.wait_done() is Outcome.FAILED
        del checked, observed
    assert _reports(caplog) == []


@action
async def slow_to_stop(robot: Robot) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(1.0)  # a long cleanup
        raise


@action
async def leaves_a_child(robot: Robot, fail: bool) -> str:
    slow_to_stop(robot)
    await robot.sleep(0.1)
    if fail:
        raise RuntimeError("arm jammed")
    return "body done"


async def test_cancel_while_the_children_wind_up_makes_a_success_cancelled() -> None:
    async with Robot() as robot:
        parent = leaves_a_child(robot, fail=False)
        await robot.sleep(0.5)  # its body has ended; its child's cleanup runs
        assert parent.state.value == "finishing"
        assert parent.cancel("stop everything")
        with pytest.raises(ActionInterrupted) as info:
            await parent
        assert info.value.reason == "stop everything"
        assert parent.outcome is Outcome.CANCELLED
        assert parent.finished_at == pytest.approx(1.1)


async def test_cancel_while_the_children_wind_up_never_masks_a_failure() -> None:
    async with Robot() as robot:
        parent = leaves_a_child(robot, fail=True)
        await robot.sleep(0.5)
        parent.cancel("stop everything")
        with pytest.raises(RuntimeError, match="arm jammed"):
            await parent
        assert parent.outcome is Outcome.FAILED
