"""Predicates: re-evaluated on writes of the keys they read, async ones in a task, poll."""

from __future__ import annotations

import asyncio
import logging

import pytest

from pyrobots_aio import Robot, UnknownStateKeyError

pytestmark = pytest.mark.virtual_time


@pytest.mark.asyncio
async def test_a_predicate_is_evaluated_on_writes_of_the_keys_it_reads_only() -> None:
    evaluations: list[tuple[float, float]] = []

    def too_close(robot: Robot) -> bool:
        left, right = robot.state.ir_left, robot.state.ir_right
        evaluations.append((left, right))
        return bool(min(left, right) < 0.2)

    async with Robot() as robot:
        robot.state.update(ir_left=1.0, ir_right=1.0, battery=0.9)
        monitor = robot.whenever(too_close, max_firing_freq=0)
        assert evaluations == [(1.0, 1.0)]  # once at creation
        robot.state.battery = 0.8
        robot.state.battery = 0.7
        robot.state.ir_left = 0.5
        robot.state.ir_right = 0.1
        robot.state.update(ir_left=0.15, ir_right=0.3)  # one batch: one evaluation
        await robot.sleep(0)
        assert evaluations == [(1.0, 1.0), (0.5, 1.0), (0.5, 0.1), (0.15, 0.3)]
        assert monitor.firings == 2


@pytest.mark.asyncio
async def test_a_predicate_watches_the_keys_it_read_at_its_last_evaluation() -> None:
    evaluations = 0

    def blocked(robot: Robot) -> bool:
        nonlocal evaluations
        evaluations += 1
        return bool(robot.state.bumper or robot.state.cliff)  # reads cliff only if not bumper

    async with Robot() as robot:
        robot.state.update(bumper=True, cliff=False)
        monitor = robot.whenever(blocked, max_firing_freq=0)
        await robot.sleep(0)  # fires: bumper
        robot.state.cliff = True  # not read last time: no evaluation
        assert evaluations == 1
        robot.state.bumper = False  # now cliff is read too
        robot.state.cliff = False
        assert evaluations == 3
        await robot.sleep(0)
        assert monitor.firings == 2  # bumper, then cliff (while it held: max_firing_freq=0)


@pytest.mark.asyncio
async def test_a_sync_predicate_sees_single_write_pulses() -> None:
    async with Robot() as robot:
        robot.state.button = False
        monitor = robot.whenever(lambda r: r.state.button)
        for _ in range(30):
            robot.state.button = True
            robot.state.button = False
            await robot.sleep(0.5)
        assert monitor.firings == 30


@pytest.mark.asyncio
async def test_an_async_predicate_runs_in_a_task_and_coalesces_re_evaluations() -> None:
    seen: list[float] = []

    async def far_from_dock(robot: Robot) -> bool:
        distance = robot.state.distance
        seen.append(distance)
        await robot.sleep(0.1)  # e.g. asks a planner
        return bool(distance > 2.0)

    async with Robot() as robot:
        robot.state.distance = 0.0
        t0 = robot.time()
        monitor = robot.whenever(far_from_dock, max_firing_freq=0)
        await robot.sleep(0.05)
        for distance in (1.0, 2.5, 3.0):  # during the first evaluation
            robot.state.distance = distance
        await robot.sleep(1.0)
        assert seen == [0.0, 3.0]  # the three writes: one more evaluation
        assert monitor.firings == 1
        fired_at = robot.time()
        robot.state.distance = 1.0
        await robot.sleep(1.0)
        assert seen == [0.0, 3.0, 1.0]
    assert fired_at - t0 == pytest.approx(1.05)


@pytest.mark.asyncio
async def test_an_async_predicate_fires_at_the_end_of_its_evaluation() -> None:
    fired: list[float] = []

    async def heavy(robot: Robot) -> bool:
        await robot.sleep(0.25)
        return bool(robot.state.payload > 1.0)

    async with Robot() as robot:
        robot.state.payload = 0.0
        t0 = robot.time()
        robot.whenever(heavy).do(lambda: fired.append(robot.time() - t0))
        await robot.sleep(1.0)
        robot.state.payload = 2.0
        await robot.sleep(0.3)
    assert fired == [pytest.approx(1.25)]


@pytest.mark.asyncio
async def test_poll_re_evaluates_a_time_dependent_predicate() -> None:
    fired: list[float] = []
    async with Robot() as robot:
        t0 = robot.time()
        robot.on(lambda r: r.time() - t0 >= 2.2, poll=0.5).do(
            lambda: fired.append(robot.time() - t0)
        )
        await robot.sleep(5.0)
    assert fired == [2.5]


@pytest.mark.asyncio
async def test_poll_and_key_changes_both_drive_a_predicate() -> None:
    evaluations: list[float] = []

    def check(robot: Robot) -> bool:
        evaluations.append(robot.time() - t0)
        return bool(robot.state.alarm)

    async with Robot() as robot:
        robot.state.alarm = False
        t0 = robot.time()
        monitor = robot.whenever(check, poll=1.0)
        await robot.sleep(1.5)
        robot.state.alarm = True
        await robot.sleep(1.0)
        monitor.stop_monitoring()
        await robot.sleep(5)
    assert evaluations == [0.0, 1.0, 1.5, 2.0]


@pytest.mark.asyncio
async def test_a_predicate_with_held_for() -> None:
    fired: list[float] = []
    async with Robot() as robot:
        robot.state.ir = 1.0
        t0 = robot.time()
        robot.whenever(lambda r: r.state.ir < 0.3, held_for=2.0).do(
            lambda: fired.append(robot.time() - t0)
        )
        robot.state.ir = 0.2
        await robot.sleep(1.0)
        robot.state.ir = 0.5
        robot.state.ir = 0.1
        await robot.sleep(2.05)
        robot.state.ir = 1.0
        await robot.sleep(1.0)
    assert fired == [3.0]


@pytest.mark.asyncio
async def test_a_sync_predicate_failing_at_creation_raises_there() -> None:
    evaluations = 0

    def too_close(robot: Robot) -> bool:
        nonlocal evaluations
        evaluations += 1
        return bool(min(robot.state.ir_left, robot.state.ir_center) < 0.2)  # ir_left is read

    async with Robot() as robot:
        robot.state.update(ir_left=1.0, ir_right=1.0)
        with pytest.raises(UnknownStateKeyError) as error:
            robot.whenever(too_close)
        assert str(error.value) == (
            "unknown state key 'ir_center'; closest: ['ir_left']; "
            "known keys: ['ir_left', 'ir_right']"
        )
        assert robot.events.monitors() == []
        assert evaluations == 1
        robot.state.ir_left = 0.1  # the key it read: nothing watches it any more
        await robot.sleep(1)
        assert evaluations == 1


@pytest.mark.asyncio
async def test_a_predicate_failing_later_is_logged_once_until_it_succeeds(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.state.divisor = 1.0
        monitor = robot.whenever(lambda r: 1 / r.state.divisor > 2, max_firing_freq=0)
        for divisor in (0.0, 0.0, 0.25, 0.0):
            robot.state.divisor = divisor
        await robot.sleep(0)
        assert monitor.firings == 1
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    message = "<lambda>: the predicate failed (logged once until it succeeds again)"
    assert [r.getMessage() for r in records] == [message] * 2
    assert all(r.exc_info and r.exc_info[0] is ZeroDivisionError for r in records)


@pytest.mark.asyncio
async def test_an_async_predicate_failing_is_logged(caplog: pytest.LogCaptureFixture) -> None:
    async def broken(robot: Robot) -> bool:
        await asyncio.sleep(0)
        raise OSError("planner offline")

    async with Robot() as robot:
        monitor = robot.whenever(broken)
        await robot.sleep(1)
        assert monitor.firings == 0
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    assert [r.getMessage() for r in records] == [
        "broken: the predicate failed (logged once until it succeeds again)",
        "broken: the predicate read no state key and has no poll=; it will not be "
        "evaluated again (read robot.state, or give poll=SECONDS)",
    ]


@pytest.mark.asyncio
async def test_a_predicate_that_reads_no_key_and_has_no_poll_is_warned_about(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        robot.whenever(lambda r: False)
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    assert [(r.levelno, r.getMessage()) for r in records] == [
        (
            logging.WARNING,
            "<lambda>: the predicate read no state key and has no poll=; it will not be "
            "evaluated again (read robot.state, or give poll=SECONDS)",
        )
    ]


async def planner_says_go(robot: Robot) -> bool:
    await robot.sleep(0.5)  # asks a planner; reads no state key
    return False


@pytest.mark.asyncio
async def test_an_async_predicate_that_reads_no_key_and_has_no_poll_is_warned_about(
    caplog: pytest.LogCaptureFixture,
) -> None:
    def logged() -> list[tuple[int, str]]:
        return [
            (r.levelno, r.getMessage()) for r in caplog.records if r.name == "pyrobots_aio.events"
        ]

    async with Robot() as robot:
        robot.whenever(planner_says_go)
        await robot.sleep(0.4)
        assert logged() == []  # its first evaluation has not ended
        await robot.sleep(0.2)
        assert logged() == [
            (
                logging.WARNING,
                "planner_says_go: the predicate read no state key and has no poll=; it will not "
                "be evaluated again (read robot.state, or give poll=SECONDS)",
            )
        ]


@pytest.mark.asyncio
async def test_an_async_predicate_that_reads_a_key_polls_or_is_done_is_not_warned_about(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def low_battery(robot: Robot) -> bool:
        await robot.sleep(0.5)
        return bool(robot.state.battery < 0.2)

    async def planner_ready(robot: Robot) -> bool:
        await robot.sleep(0.5)
        return True

    async with Robot() as robot:
        robot.state.battery = 1.0
        robot.whenever(low_battery)
        robot.whenever(planner_says_go, poll=1.0)
        assert await robot.wait(planner_ready) is True  # a one-shot done at once
        await robot.sleep(2.0)
    assert [r for r in caplog.records if r.name == "pyrobots_aio.events"] == []


@pytest.mark.asyncio
async def test_stopping_cancels_a_running_async_evaluation() -> None:
    finished: list[bool] = []

    async def slow(robot: Robot) -> bool:
        await robot.sleep(10)
        finished.append(True)
        return True

    async with Robot() as robot:
        monitor = robot.whenever(slow)
        await robot.sleep(1)
        monitor.stop_monitoring()
        await robot.sleep(20)
    assert finished == []


@pytest.mark.asyncio
async def test_writes_during_an_async_evaluation_are_coalesced_into_one_more() -> None:
    seen: list[int] = []

    async def check(robot: Robot) -> bool:
        value = robot.state.counter
        seen.append(value)
        await robot.sleep(1.0)
        return False

    async with Robot() as robot:
        robot.state.counter = 0
        robot.whenever(check)
        await robot.sleep(1.5)  # the first evaluation is over: counter is watched
        for value in (1, 2, 3):
            robot.state.counter = value
            await robot.sleep(0.1)  # all during the second evaluation
        await robot.sleep(5.0)
    assert seen == [0, 1, 3]


class Ambiguous:
    def __bool__(self) -> bool:
        raise ValueError("the truth value of an array is ambiguous")


@pytest.mark.asyncio
async def test_a_result_without_a_truth_value_is_logged(caplog: pytest.LogCaptureFixture) -> None:
    async with Robot() as robot:
        robot.state.scan = 0
        monitor = robot.whenever(lambda r: Ambiguous() if r.state.scan else True)
        await robot.sleep(0)
        robot.state.scan = 1
        await robot.sleep(0)
        assert monitor.firings == 1
    records = [r for r in caplog.records if r.name == "pyrobots_aio.events"]
    assert len(records) == 1
    assert records[0].getMessage().startswith("<lambda>: bool() of its result <")
