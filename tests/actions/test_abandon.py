"""An action that ignores every cancel: shutdown and the process still end; its resources wait."""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import logging

import pytest

from pyrobots_aio import Outcome, Resource, Robot, action, lock
from pyrobots_aio.sim import run

WHEELS = Resource("wheels")


@action
async def deaf(robot: Robot) -> None:
    while True:
        with contextlib.suppress(asyncio.CancelledError):  # swallows every cancel
            await asyncio.sleep(10)


@action
async def spinning(robot: Robot) -> None:
    while True:
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.sleep(0)  # polls without ever waiting


def _line_of(fn: object, text: str) -> str:
    """``file:line`` of the line of ``fn``'s source containing ``text``."""
    lines, first = inspect.getsourcelines(fn)  # type: ignore[arg-type]
    offset = next(n for n, line in enumerate(lines) if text in line)
    return f"{inspect.getsourcefile(fn)}:{first + offset}"  # type: ignore[arg-type]


def _errors(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno >= logging.ERROR]


def test_asyncio_run_ends_after_an_action_that_ignores_every_cancel(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def main() -> None:
        async with Robot(cancel_grace=0.05) as robot:
            deaf(robot)
            await asyncio.sleep(0.01)

    asyncio.run(main())  # returns: no task is left for asyncio.run to wait for
    (error,) = _errors(caplog)
    assert error == (
        f"action deaf#1 ignored cancellation for 0.1 s, at {_line_of(deaf.fn, 'sleep(10)')}; "
        "abandoning it (its body is ended; its resources stay held until its task ends)"
    )


def test_sim_run_ends_after_an_action_that_ignores_every_cancel(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def main() -> float:
        async with Robot() as robot:
            deaf(robot)
            await asyncio.sleep(1)
        return robot.time() if robot.is_running else asyncio.get_running_loop().time()

    assert run(main) == 5.0  # 1 s, then two graces of 2 s
    assert len(_errors(caplog)) == 1


def test_a_lockstep_action_polling_with_sleep_0_does_not_freeze_virtual_time(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async def main() -> float:
        async with Robot() as robot:
            spinning(robot)
            await asyncio.sleep(1)
        return asyncio.get_running_loop().time()

    assert run(main) >= 5.0  # the watchdog fired: time moved while the loop was busy
    warnings = [r.getMessage() for r in caplog.records if r.name == "pyrobots_aio.clock"]
    assert warnings == [
        "virtual time: the event loop ran 100000 iterations in a row without waiting (a task "
        "polling with 'await asyncio.sleep(0)'?); from now on, while it stays busy, each "
        "iteration lets virtual time reach the next timer"
    ]
    (error,) = _errors(caplog)
    assert error.startswith("action spinning#1 ignored cancellation for 4 s, at ")


@action
@lock(WHEELS)
async def stubborn_driver(robot: Robot, release: asyncio.Event, log: list[str]) -> None:
    while not release.is_set():
        try:
            await release.wait()
        except BaseException:
            log.append("ignored")
    log.append("ended")


@action
@lock(WHEELS)
async def next_driver(robot: Robot) -> str:
    return "got the wheels"


@pytest.mark.asyncio
@pytest.mark.virtual_time
@pytest.mark.allow_leaks
async def test_an_abandoned_holder_keeps_its_resources_until_its_task_ends(
    caplog: pytest.LogCaptureFixture,
) -> None:
    release = asyncio.Event()
    log: list[str] = []
    async with Robot(cancel_grace=1.0) as robot:
        stubborn = stubborn_driver(robot, release, log)
        await robot.sleep(0.1)
        waiter = next_driver(robot)
        stubborn.cancel("stop")
        assert await stubborn.wait_done() is Outcome.CANCELLED  # abandoned after 2 graces
        await robot.sleep(1)
        assert robot.resources.owner(WHEELS) is stubborn  # still held: its code still runs
        assert repr(robot.resources) == (
            "<ResourceManager 'wheels' held by stubborn_driver#1 (abandoned, its task still "
            "running), waiters [next_driver#2]>"
        )
        assert not waiter.done()
        release.set()  # now its task ends ...
        assert await waiter == "got the wheels"  # ... and only then the wheels pass on
    assert log[-1] == "ended"
    assert "resisted being abandoned" in " ".join(_errors(caplog))
