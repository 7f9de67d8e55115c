"""Log levels are per robot; a forgotten ``await`` is pointed out at exit."""

from __future__ import annotations

import asyncio
import logging

import pytest

from log_support import logged
from pyrobots_aio import ActionCancelled, Robot, action

pytestmark = pytest.mark.virtual_time


@action
async def stubborn(robot: Robot) -> None:
    """Ignores the first cancellation (so the watchdog warns)."""
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(3600)


@action
async def nap(robot: Robot) -> None:
    await robot.sleep(1)


async def _warn_once(robot: Robot) -> None:
    """Make the executive log one warning about this robot (cancel_grace is 1 s)."""
    handle = stubborn(robot)
    await robot.sleep(0.1)
    handle.cancel("stop")
    await handle.wait_done()


def _warnings_of(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [
        r.getMessage().split(" still running")[0]
        for r in caplog.records
        if r.levelno == logging.WARNING and "still running" in r.getMessage()
    ]


@pytest.mark.asyncio
async def test_a_level_set_on_one_robot_leaves_the_other_s_records(
    caplog: pytest.LogCaptureFixture,
) -> None:
    quiet, loud = Robot(cancel_grace=1.0), Robot(cancel_grace=1.0)
    quiet.loglevel(logging.ERROR)
    async with quiet, loud:
        await _warn_once(quiet)
        await _warn_once(loud)
    assert _warnings_of(caplog) == ["action stubborn#1"]  # loud's; quiet's was dropped
    assert logging.getLogger("pyrobots_aio").level == logging.NOTSET  # no logger touched


def _broken() -> None:
    raise ValueError("servo unplugged")


async def _say_a_bit_of_everything(robot: Robot) -> None:
    """Make the library log about ``robot`` at every level, DEBUG to ERROR."""
    robot._log_scope.logger("pyrobots_aio.robot").debug("a detail")
    robot.state.bumper = False
    robot.whenever("bumper", becomes=True).do(_broken)  # ERROR, at the next loop iteration
    robot.state.bumper = True
    await robot.emergency_stop("operator")  # WARNING, at once
    robot.clear_emergency_stop()  # INFO
    nap(robot)  # forgot 'await': a WARNING at exit


@pytest.mark.asyncio
async def test_silent_keeps_what_went_wrong_and_drops_info_and_debug_of_that_robot_only(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.DEBUG, logger="pyrobots_aio")  # the user's handlers take it all
    quiet, loud = Robot(), Robot()
    quiet.silent()  # pyRobots: an alias for loglevel(WARNING)
    async with quiet:
        await _say_a_bit_of_everything(quiet)
    async with loud:
        await _say_a_bit_of_everything(loud)
    said = [
        (r.levelname, r.getMessage()) for r in logged(caplog) if r.name.startswith("pyrobots_aio.")
    ]
    went_wrong = [
        ("WARNING", "emergency stop: operator; preempting nothing"),
        ("ERROR", "callback _broken of monitor 'bumper becomes=True' failed"),
        ("WARNING", "action nap#2 is cancelled by the robot's exit before it ever ran, and "
         "nothing waits for it: a missing 'await'? (await the handle before leaving "
         "'async with robot:')"),
    ]  # fmt: skip
    assert said == [
        *went_wrong,
        ("DEBUG", "a detail"),
        *went_wrong[:2],
        ("INFO", "emergency stop cleared (it was: operator)"),
        went_wrong[2],
    ]


@pytest.mark.asyncio
async def test_debug_on_one_robot_passes_its_records_whatever_the_logger_level(
    caplog: pytest.LogCaptureFixture,
) -> None:
    logger = logging.getLogger("pyrobots_aio")
    logger.setLevel(logging.ERROR)  # the user's configuration: errors only
    chatty, plain = Robot(cancel_grace=1.0), Robot(cancel_grace=1.0)
    chatty.debug()
    try:
        async with chatty, plain:
            await _warn_once(chatty)
            await _warn_once(plain)
    finally:
        logger.setLevel(logging.NOTSET)
    assert _warnings_of(caplog) == ["action stubborn#1"]
    record = next(r for r in caplog.records if "still running" in r.getMessage())
    assert record.name == "pyrobots_aio.actions"
    assert record.funcName == "_overdue"  # the library's call site, not the log scope's


def test_loglevel_takes_names_and_numbers_and_refuses_the_rest() -> None:
    robot = Robot()
    robot.loglevel("warning")
    robot.loglevel(logging.INFO)
    robot.loglevel(None)
    with pytest.raises(ValueError, match="unknown log level 'loud'; use one of DEBUG, INFO"):
        robot.loglevel("loud")
    with pytest.raises(ValueError, match="unknown log level -1"):
        robot.loglevel(-1)


@pytest.mark.asyncio
async def test_an_action_the_exit_cancels_before_it_ran_hints_at_a_missing_await(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        nap(robot)  # forgot 'await'
    assert [r.getMessage() for r in logged(caplog, logging.WARNING)] == [
        "action nap#1 is cancelled by the robot's exit before it ever ran, and nothing waits "
        "for it: a missing 'await'? (await the handle before leaving 'async with robot:')"
    ]


@pytest.mark.asyncio
async def test_no_hint_when_the_action_ran_was_awaited_or_was_cancelled_on_purpose(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        ran = nap(robot)
        await asyncio.sleep(0)  # its body started
        nap(robot).cancel("on purpose")
        watched = nap(robot)
        waiter = asyncio.create_task(watched.wait_done())
        await asyncio.sleep(0)
    await waiter
    assert ran.started_at is not None
    assert logged(caplog, logging.WARNING) == []
