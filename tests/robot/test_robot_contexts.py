"""Wrong thread, wrong loop, wrong library; the thread-safe ways in; robot.state stays put."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable, Coroutine
from typing import Any

import anyio
import pytest

from pyrobots_aio import EventLoopError, Outcome, PyRobotsError, Robot, action

THREADSAFE = (
    "robot.call_soon_threadsafe(fn, *args) or robot.run_threadsafe(coro) "
    "(asyncio.run_coroutine_threadsafe), or anyio.from_thread.run(...) from an anyio worker thread"
)


@action
async def nap(robot: Robot, seconds: float = 0.01) -> str:
    await robot.sleep(seconds)
    return "rested"


async def _in_thread(fn: Callable[[], object]) -> BaseException | None:
    """Run ``fn`` in a worker thread named 'worker'; return what it raised."""
    raised: list[BaseException] = []

    def target() -> None:
        try:
            fn()
        except BaseException as exc:
            raised.append(exc)

    worker = threading.Thread(target=target, name="worker")
    worker.start()
    await asyncio.to_thread(worker.join)
    return raised[0] if raised else None


@pytest.mark.asyncio
async def test_starting_an_action_from_a_worker_thread_says_how() -> None:
    async with Robot() as robot:
        error = await _in_thread(lambda: nap(robot))
        assert isinstance(error, EventLoopError)
        loop_thread = threading.current_thread().name
        assert str(error) == (
            f"cannot start action 'nap' from thread 'worker': the robot runs on the event loop "
            f"of thread {loop_thread!r}; from another thread, use {THREADSAFE}"
        )
        assert robot.handles() == []


@pytest.mark.asyncio
async def test_monitors_and_awaits_from_a_worker_thread_say_how() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        handle = nap(robot, 0.5)
        monitor_error = await _in_thread(lambda: robot.whenever("bumper", becomes=True))
        assert isinstance(monitor_error, EventLoopError)
        assert str(monitor_error).startswith("cannot monitor 'bumper' from thread 'worker'")
        await_error = await _in_thread(lambda: asyncio.run(handle.wait_done()))
        assert isinstance(await_error, EventLoopError)
        assert str(await_error).startswith(
            "cannot wait for action nap#1 from thread 'worker': the robot runs on the event loop"
        )
        assert robot.events.monitors() == []
        assert await handle == "rested"


@pytest.mark.asyncio
async def test_writing_state_from_a_worker_thread_says_how() -> None:
    robot = Robot()
    robot.state.mode = "idle"  # before the robot runs, from anywhere
    async with robot:
        single = await _in_thread(lambda: robot.state.update(mode="busy"))
        attribute = await _in_thread(lambda: setattr(robot.state, "mode", "busy"))
        assert isinstance(single, EventLoopError)
        assert isinstance(attribute, EventLoopError)
        assert str(single).startswith("cannot write state keys ['mode'] from thread 'worker'")
        assert str(attribute).startswith("cannot write state key 'mode' from thread 'worker'")
        assert THREADSAFE in str(single)
        assert robot.state.mode == "idle"  # nothing was written
        robot.call_soon_threadsafe(robot.state.update, {"mode": "busy"})  # the way in
        await asyncio.sleep(0)
        assert robot.state.mode == "busy"
    await _in_thread(lambda: robot.state.update(mode="off"))  # stopped: from anywhere again
    assert robot.state.mode == "off"


@pytest.mark.asyncio
async def test_cancel_pause_and_resume_from_a_worker_thread_say_how() -> None:
    async with Robot() as robot:
        handle = nap(robot, 3600)
        await asyncio.sleep(0)
        cancel = await _in_thread(lambda: handle.cancel("from the worker"))
        pause = await _in_thread(lambda: handle.pause("from the worker"))
        resume = await _in_thread(handle.resume)
        loop_thread = threading.current_thread().name
        assert isinstance(cancel, EventLoopError)
        assert str(cancel) == (
            f"cannot cancel action nap#1 from thread 'worker': the robot runs on the event loop "
            f"of thread {loop_thread!r}; from another thread, use {THREADSAFE}"
        )
        assert isinstance(pause, EventLoopError)
        assert str(pause).startswith("cannot pause action nap#1 from thread 'worker'")
        assert isinstance(resume, EventLoopError)
        assert str(resume).startswith("cannot resume action nap#1 from thread 'worker'")
        await asyncio.sleep(0)  # nothing was left to land when the loop wakes
        assert not handle.cancel_requested
        assert not handle.paused
        await _in_thread(lambda: robot.call_soon_threadsafe(handle.cancel, "from the worker"))
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.cancel_reason == "from the worker"
        assert await _in_thread(handle.cancel) is None  # done: nothing to do, from anywhere
        assert handle.cancel() is False


@pytest.mark.asyncio
async def test_pausing_all_and_the_emergency_stop_from_a_worker_thread_say_how() -> None:
    async with Robot() as robot:
        handle = nap(robot, 3600)
        await asyncio.sleep(0)
        pause_all = await _in_thread(robot.pause_all)
        resume_all = await _in_thread(robot.resume_all)
        stop = await _in_thread(robot.emergency_stop)
        assert str(pause_all).startswith("cannot call robot.pause_all from thread 'worker'")
        assert str(resume_all).startswith("cannot call robot.resume_all from thread 'worker'")
        assert str(stop).startswith("cannot emergency stop from thread 'worker'")
        assert not handle.paused
        assert not robot.emergency_stopped
        await robot.emergency_stop("operator")
        clear = await _in_thread(robot.clear_emergency_stop)
        assert isinstance(clear, EventLoopError)
        assert str(clear) == (
            f"cannot clear the emergency stop from thread 'worker': the robot runs on the event "
            f"loop of thread {threading.current_thread().name!r}; from another thread, use "
            f"{THREADSAFE}"
        )
        assert robot.emergency_stopped  # still latched, its state keys with it
        assert robot.state.emergency_stop is True
        handle.cancel()
    assert await _in_thread(robot.clear_emergency_stop) is None  # stopped: from anywhere
    assert not robot.emergency_stopped
    assert robot.state.emergency_stop is False


@pytest.mark.asyncio
async def test_the_threadsafe_ways_in_work_from_a_worker_thread() -> None:
    async with Robot() as robot:
        robot.state.mode = "idle"
        started: list[Any] = []

        async def drive_and_report() -> str:
            result = await nap(robot, 0.05)
            robot.state.mode = "busy"
            return result

        def from_worker() -> None:
            robot.call_soon_threadsafe(lambda: started.append(nap(robot, 0.05)))
            started.append(robot.run_threadsafe(drive_and_report()).result(timeout=30))

        assert await _in_thread(from_worker) is None
        handle, result = started
        assert result == "rested"
        assert await handle == "rested"
        assert robot.state.mode == "busy"


@pytest.mark.asyncio
async def test_run_threadsafe_on_the_robot_s_own_loop_is_refused() -> None:
    async with Robot() as robot:

        async def noop() -> None:
            return None

        with pytest.raises(EventLoopError, match=r"run_threadsafe\(\) is for other threads"):
            robot.run_threadsafe(noop())


@pytest.mark.asyncio
async def test_awaiting_a_handle_from_another_event_loop_says_so() -> None:
    async with Robot() as robot:
        handle = nap(robot, 0.5)

        def other_loop() -> None:
            asyncio.run(handle.wait_done())

        error = await _in_thread(other_loop)
        assert isinstance(error, EventLoopError)
        assert "from thread 'worker'" in str(error)
        assert await handle.wait_done() is Outcome.SUCCEEDED


def test_a_robot_under_trio_says_it_needs_asyncio() -> None:
    async def main() -> None:
        async with Robot():
            pass

    with pytest.raises(EventLoopError) as caught:
        anyio.run(main, backend="trio")
    assert str(caught.value) == (
        "cannot run Robot under trio: pyrobots_aio needs asyncio; "
        'use anyio.run(..., backend="asyncio")'
    )


def test_a_robot_under_anyio_s_asyncio_backend_runs() -> None:
    async def main() -> str:
        async with Robot() as robot:
            return await nap(robot)

    assert anyio.run(main, backend="asyncio") == "rested"


def test_a_robot_entered_with_no_event_loop_says_so() -> None:
    robot = Robot()
    coro: Coroutine[Any, Any, Robot] = robot.__aenter__()
    with pytest.raises(EventLoopError, match=r"no asyncio event loop is running in thread"):
        coro.send(None)


@pytest.mark.asyncio
async def test_robot_state_cannot_be_replaced_and_monitors_keep_working() -> None:
    fired: list[bool] = []
    async with Robot() as robot:
        robot.state.bumper = False
        robot.whenever("bumper", becomes=True).do(fired.append, True)
        store = robot.state
        with pytest.raises(AttributeError) as caught:
            robot.state = {"bumper": True}  # type: ignore[assignment]
        assert str(caught.value) == (
            "robot.state cannot be replaced (got dict): monitors and the backend watch this "
            "store; write values into it, e.g. robot.state.update(...)"
        )
        assert robot.state is store
        robot.state.update({"bumper": True})
        await asyncio.sleep(0)
    assert fired == [True]


def test_a_second_async_with_is_refused_while_running() -> None:
    async def main() -> None:
        async with Robot() as robot:
            with pytest.raises(PyRobotsError, match="already running"):
                await robot.__aenter__()

    asyncio.run(main())
