"""Failures: reported when nobody retrieves them, not when somebody does; finishing-phase cancel."""

from __future__ import annotations

import asyncio
import gc
import traceback

import pytest

from pyrobots_aio import Action, ActionCancelled, ActionInterrupted, Outcome, Robot, action
from pyrobots_aio.actions import current_action

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

UNRETRIEVED = "failed and nobody retrieved its error:"


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


@action
async def waits_for_its_child(robot: Robot) -> None:
    await quick(robot)  # cancelled by someone else: its ActionInterrupted escapes


@action
async def wraps_interruption(robot: Robot) -> None:
    try:
        await quick(robot)
    except ActionInterrupted as stop:
        raise RuntimeError("gave up") from stop


def _reports(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if UNRETRIEVED in r.getMessage()]


async def test_a_failure_retrieved_later_is_never_reported(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        first, second = quick(robot), boom(robot, 0.1)
        assert await first == "done"  # meanwhile the second failed, with nobody waiting yet
        with pytest.raises(RuntimeError, match="servo unplugged"):
            await second
        del first, second
    gc.collect()
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
        (report,) = _reports(caplog)
    lines = report.splitlines()
    assert lines[0] == f"action boom#1 {UNRETRIEVED}"
    assert lines[1] == "Traceback (most recent call last):"
    assert "in boom" in lines[2]  # it starts in the action's own code
    assert lines[3].strip() == 'raise RuntimeError("servo unplugged")'
    assert lines[-1] == "RuntimeError: servo unplugged"


async def test_failures_whose_errors_refer_to_handles_are_reported_by_the_collector(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Cycles (a frame holding its own handle, a child's interruption) wait for the collector."""
    async with Robot() as robot:
        boom_knowing_itself(robot)
        waits_for_its_child(robot)
        wraps_interruption(robot)
        await robot.sleep(0.1)
        for child in [h for h in robot.handles() if h.name == "quick"]:
            child.cancel("enough")  # the error of its parent will refer to it, and so back
        del child
        await robot.sleep(1.0)
    gc.collect()
    firsts = sorted(report.splitlines()[0] for report in _reports(caplog))
    assert firsts == [
        f"action boom_knowing_itself#1 {UNRETRIEVED}",
        f"action waits_for_its_child#2 {UNRETRIEVED}",
        f"action wraps_interruption#3 {UNRETRIEVED}",
    ]


async def test_reporting_a_failure_leaves_the_coroutines_in_its_traceback_alone() -> None:
    """A service still running appears in the traceback; it must keep running."""
    requests: asyncio.Queue[asyncio.Future[None]] = asyncio.Queue()

    async def service() -> None:
        while True:
            reply = await requests.get()
            try:
                raise ConnectionError("arm controller offline")
            except ConnectionError as error:
                reply.set_exception(error)  # the traceback holds this suspended frame

    @action
    async def ask(robot: Robot) -> None:
        reply = asyncio.get_running_loop().create_future()
        requests.put_nowait(reply)
        await reply

    server = asyncio.create_task(service())
    async with Robot() as robot:
        ask(robot)  # forgotten: its failure is reported
        await robot.sleep(0.1)
        assert not server.done()
        again = asyncio.get_running_loop().create_future()
        requests.put_nowait(again)
        with pytest.raises(ConnectionError):
            await again
    server.cancel()
    with pytest.raises(asyncio.CancelledError):
        await server


async def test_exception_and_wait_done_retrieve_the_failure(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Robot() as robot:
        checked, observed = boom(robot, 0.1), boom(robot, 0.1)
        await robot.sleep(1.0)
        assert isinstance(checked.exception(), RuntimeError)
        assert await observed.wait_done() is Outcome.FAILED
        del checked, observed
    gc.collect()
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


@action
async def fails_at_once(robot: Robot) -> None:
    raise ValueError("bad gain")


@action
async def fails_after_a_raw_await(robot: Robot) -> None:
    await asyncio.sleep(1)
    raise ValueError("bad gain")


@pytest.mark.parametrize("pause", [False, True], ids=["running", "paused-then-resumed"])
@pytest.mark.parametrize("body", [fails_at_once, fails_after_a_raw_await], ids=lambda a: a.name)
async def test_a_failure_traceback_starts_in_the_body(
    body: Action[Robot, [], None], pause: bool
) -> None:
    # The executive's frames (the task's coroutine and the pause trampoline) hold the
    # handle: they are cut off, whether the body failed on its first step or later.
    async with Robot() as robot:
        handle = body(robot)
        if pause:
            handle.pause()
            await robot.sleep(2)
            handle.resume()
        await handle.wait_done()
    error = handle.exception()
    assert isinstance(error, ValueError)
    frames = traceback.extract_tb(error.__traceback__)
    assert frames[0].name == body.name
    assert not [f for f in frames if "pyrobots_aio" in f.filename]
