"""A running robot takes SIGINT and SIGTERM over (unless told not to, or they are taken)."""

from __future__ import annotations

import asyncio
import os
import signal
import threading

import pytest

from pyrobots_aio import Robot, action


def _handlers() -> tuple[object, object]:
    return signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)


@pytest.mark.asyncio
async def test_the_robot_takes_the_signals_while_it_runs_and_gives_them_back() -> None:
    before = _handlers()
    async with Robot():
        assert _handlers() != before  # the loop's handlers (set_wakeup_fd) stand in
    assert _handlers() == before


@pytest.mark.asyncio
async def test_handle_signals_false_leaves_them_alone() -> None:
    before = _handlers()
    async with Robot(handle_signals=False):
        assert _handlers() == before
    assert _handlers() == before


@pytest.mark.asyncio
async def test_a_signal_the_program_handles_is_left_alone() -> None:
    def own(signum: int, frame: object) -> None:
        raise AssertionError("not sent in this test")

    previous = signal.signal(signal.SIGTERM, own)
    try:
        async with Robot():
            assert signal.getsignal(signal.SIGTERM) is own
        assert signal.getsignal(signal.SIGTERM) is own
    finally:
        signal.signal(signal.SIGTERM, previous)


@pytest.mark.asyncio
async def test_sigterm_stops_the_robot_in_order_and_raises_system_exit_143() -> None:
    cleaned: list[str] = []

    @action
    async def hold(robot: Robot) -> None:
        try:
            await asyncio.sleep(60)
        except asyncio.CancelledError:
            await asyncio.sleep(0.01)  # cleanup that awaits
            cleaned.append("hold")
            raise

    async def main() -> None:
        async with Robot(actions=[hold]) as robot:
            robot.hold()
            await asyncio.sleep(0.01)
            os.kill(os.getpid(), signal.SIGTERM)
            await asyncio.sleep(60)

    before = _handlers()
    with pytest.raises(SystemExit) as ended:
        await main()
    assert ended.value.code == 143
    assert cleaned == ["hold"]
    assert _handlers() == before


def test_a_robot_off_the_main_thread_leaves_the_signals_alone() -> None:
    before = _handlers()
    during: list[tuple[object, object]] = []

    async def main() -> None:
        async with Robot():
            during.append(_handlers())

    worker = threading.Thread(target=asyncio.run, args=(main(),))
    worker.start()
    worker.join()
    assert during == [before]


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_second_signal_right_after_the_first_cuts_the_cleanup_it_starts() -> None:
    # The second Ctrl-C lands before the first one's cancellation has reached the
    # actions: its own cancel starts their cleanup, which must be cut short as well.
    loop = asyncio.get_running_loop()

    @action
    async def blink(robot: Robot) -> None:
        await robot.sleep(0.01)

    @action
    async def walk(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except asyncio.CancelledError:
            end = loop.time() + 30.0  # a long, busy cleanup
            while loop.time() < end:
                await blink(robot)
            raise

    async def main() -> None:
        async with Robot(actions=[walk], cancel_grace=120) as robot:
            robot.walk()
            await asyncio.sleep(0.1)
            os.kill(os.getpid(), signal.SIGINT)
            os.kill(os.getpid(), signal.SIGINT)
            await asyncio.sleep(3600)

    start = loop.time()
    with pytest.raises(KeyboardInterrupt):
        await main()
    assert loop.time() - start < 1.0  # not the 30 s cleanup


@pytest.mark.parametrize("value", ["no", 0, None])
def test_handle_signals_must_be_a_bool(value: object) -> None:
    with pytest.raises(TypeError, match=r"handle_signals must be True or False, got"):
        Robot(handle_signals=value)  # type: ignore[arg-type]
