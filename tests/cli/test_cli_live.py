"""What the demo shows while it runs: event lines, and the live block redrawn in place."""

from __future__ import annotations

import asyncio
import contextlib
import io
from pathlib import Path

import pytest

from pyrobots_aio import ActionInterrupted, Resource, Robot, action, lock
from pyrobots_aio.cli._live import EventLines, LiveStatus, Tally, _running

WHEELS = Resource("wheels")
SOURCE = Path(__file__).read_text().splitlines()
AT = f"test_cli_live.py:{SOURCE.index('    await robot.sleep(10.0)') + 1}"  # where drive waits


@action
@lock(WHEELS)
async def drive(robot: Robot) -> None:
    await robot.sleep(10.0)


@action
@lock(WHEELS, priority=1, preempt=True)
async def reflex(robot: Robot) -> None:
    await robot.sleep(1.0)


@action
async def walk(robot: Robot) -> None:
    with contextlib.suppress(ActionInterrupted):
        await drive(robot)


@action
@lock(WHEELS, wait=False)
async def nudge(robot: Robot) -> None:
    await robot.sleep(1.0)


async def _play(*instruments: object) -> None:
    async with Robot(instruments=instruments) as robot:  # type: ignore[arg-type]
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(reflex)
        done = walk(robot)
        await robot.sleep(1.0)
        await nudge(robot).wait_done()
        robot.state.bumper = True
        await done
        await robot.sleep(1.0)  # the reflex ends


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_event_lines_tell_who_cancelled_whom_and_why() -> None:
    verbose: list[str] = []
    quiet: list[str] = []
    tally = Tally()
    await _play(
        EventLines(verbose.append, 0.0, verbose=True),
        EventLines(quiet.append, 0.0, verbose=False),
        tally,
    )
    why = "preempted by reflex#4 (priority 1) for 'wheels'"
    assert verbose == [
        "    0.000  start    walk#1",
        "    0.000  start    drive#2 under walk#1",
        "    1.000  start    nudge#3",
        "    1.000  skip     nudge#3: 'wheels' is busy",
        "    1.000  skipped  nudge#3",
        "    1.000  event    bumper becomes=True fired",
        "    1.000  start    reflex#4",
        f"    1.000  cancel   drive#2 by reflex#4: {why}",
        "    1.000  cancelled drive#2",
        "    1.000  succeeded walk#1",
        "    2.000  succeeded reflex#4",
    ]
    assert quiet == [
        "    1.000  skip     nudge#3: 'wheels' is busy",
        "    1.000  skipped  nudge#3",
        "    1.000  event    bumper becomes=True fired",
        f"    1.000  cancel   drive#2 by reflex#4: {why}",
        "    1.000  cancelled drive#2",
    ]
    assert (tally.actions, tally.cancelled, tally.failed, tally.firings) == (4, 1, 0, 1)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_the_live_block_is_erased_before_anything_is_written_above_it() -> None:
    screen = io.StringIO()
    live = LiveStatus(screen, lambda: "headline")
    async with Robot() as robot:
        robot.state.update(bumper=False, v=0.25)
        async with live.showing(robot):
            handle = drive(robot)
            await robot.sleep(0.15)  # the block is drawn at 0.1
            assert live.lines() == [
                "headline",
                "  state   bumper=False  v=+0.250",
                f"  running drive#1 running holds wheels at {AT}",
            ]
            screen.truncate(0)
            screen.seek(0)
            live.line("a log line")
            handle.cancel("done")
        assert screen.getvalue() == (
            "\x1b[3F\x1b[J"  # erase the block drawn by the refresh
            "a log line\n"
            "headline\n  state   bumper=False  v=+0.250\n"
            f"  running drive#1 running holds wheels at {AT}\n"
            "\x1b[3F\x1b[J"  # erased when the showing ends
        )
    assert live.isatty()


async def _cleaning_up(cleaning: asyncio.Future[None], release: asyncio.Future[None]) -> None:
    """Work that runs until cancelled, then takes until ``release`` to clean up."""
    try:
        await asyncio.Event().wait()
    finally:
        cleaning.set_result(None)
        await release


@pytest.mark.asyncio
async def test_showing_absorbs_only_its_own_tasks_cancellation() -> None:
    loop = asyncio.get_running_loop()
    release = loop.create_future()

    async def caller() -> str:
        async with _running(_cleaning_up(loop.create_future(), release), "work"):
            await asyncio.sleep(0)  # the work starts
            release.set_result(None)
        return "went on"

    assert await caller() == "went on"


@pytest.mark.asyncio
async def test_cancelling_the_caller_while_it_awaits_the_task_propagates() -> None:
    loop = asyncio.get_running_loop()
    cleaning: asyncio.Future[None] = loop.create_future()

    async def caller() -> str:
        async with _running(_cleaning_up(cleaning, loop.create_future()), "work"):
            await asyncio.sleep(0)  # the work starts
        return "went on"

    outer = asyncio.create_task(caller())
    await cleaning  # the body is over: the caller awaits the task's cleanup
    outer.cancel()
    with pytest.raises(asyncio.CancelledError):
        await outer
    assert outer.cancelled()
