"""A running robot takes SIGINT and SIGTERM over (unless told not to, or they are taken)."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import threading
from subprocess import PIPE
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EventKind, Robot, action
from pyrobots_aio._core import _signals
from pyrobots_aio.loops import new_virtual_loop
from pyrobots_aio.recording import load
from signal_support import HANG_GUARD, started, wait_delivered

if TYPE_CHECKING:
    from pathlib import Path


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


def test_sigterm_stops_the_robot_in_order_and_ends_the_program_with_system_exit_143() -> None:
    # As asyncio.run's KeyboardInterrupt, the end comes out of the loop once the main task
    # is done, cancelled: here, of loop.run_until_complete (on the main thread, as a program).
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

    async def afresh() -> None:
        async with Robot():  # a robot entered meanwhile takes them afresh
            assert not _signals._lingering

    before = _handlers()
    loop = asyncio.new_event_loop()
    try:
        with pytest.raises(SystemExit) as ended:
            loop.run_until_complete(main())
        assert ended.value.code == 143
        assert cleaned == ["hold"]
        # The program unwinds with the signals still taken (what encloses the robot, a
        # recorder, still has to close): the next one is a second one, not Python's default.
        assert _handlers() != before
        [stop] = _signals._lingering
        assert stop.received == [signal.SIGTERM]
        loop.run_until_complete(afresh())
        assert _handlers() == before
    finally:
        loop.close()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
@pytest.mark.asyncio
async def test_a_program_that_handles_the_cancellation_goes_on(signum: signal.Signals) -> None:
    # asyncio.run's rule: KeyboardInterrupt only if the cancellation ended the main task.
    async def main() -> str:
        async with Robot():
            try:
                os.kill(os.getpid(), signum)
                await asyncio.sleep(60)
            except asyncio.CancelledError:
                await asyncio.sleep(0.01)  # cleanup that awaits
                return "cleaned up"
        return "not cancelled"

    before = _handlers()
    assert await main() == "cleaned up"
    assert _handlers() == before
    assert asyncio.current_task().cancelling() == 0  # type: ignore[union-attr]


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


def test_a_second_signal_right_after_the_first_cuts_the_cleanup_it_starts() -> None:
    # The second Ctrl-C lands before the first one's cancellation has reached the
    # actions: its own cancel starts their cleanup, which must be cut short as well.
    loop = new_virtual_loop()

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

    try:
        start = loop.time()
        with pytest.raises(KeyboardInterrupt):
            loop.run_until_complete(main())
        assert loop.time() - start < 1.0  # not the 30 s cleanup
    finally:
        loop.close()


@pytest.mark.parametrize("value", ["no", 0, None])
def test_handle_signals_must_be_a_bool(value: object) -> None:
    with pytest.raises(TypeError, match=r"handle_signals must be True or False, got"):
        Robot(handle_signals=value)  # type: ignore[arg-type]


HANDLED = """
import asyncio
from pyrobots_aio import Robot


async def main():
    async with Robot():
        print("ready", flush=True)
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            print("cleaned up", flush=True)
    print("after the robot", flush=True)


asyncio.run(main())
print("asyncio.run returned", flush=True)
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_a_script_that_handles_the_cancellation_ends_normally(
    tmp_path: Path, signum: signal.Signals
) -> None:
    # Before: `async with Robot()` raised KeyboardInterrupt (SystemExit) anyway, and
    # the print after the block never ran (pyRobots' own Ctrl-C test script).
    script = tmp_path / "handled.py"
    script.write_text(HANDLED, encoding="utf-8")
    with started([sys.executable, str(script)], stdout=PIPE, stderr=PIPE) as child:
        assert child.stdout is not None
        assert child.stdout.readline() == "ready\n"
        child.send_signal(signum)
        out, err = child.communicate(timeout=HANG_GUARD)
    assert (child.returncode, out) == (0, "cleaned up\nafter the robot\nasyncio.run returned\n")
    again = "Ctrl-C" if signum == signal.SIGINT else signum.name
    assert err == f"{signum.name}: stopping the robot ({again} again stops at once)\n"


AROUND = """
import asyncio
import sys

from pyrobots_aio import Robot

CAUGHT = sys.argv[1] == "caught"


async def main():
    try:
        async with Robot():
            print("ready", flush=True)
            await asyncio.sleep(3600)
    except asyncio.CancelledError:
        if not CAUGHT:
            raise
        print("cleaned up around the robot", flush=True)
    print("after the robot", flush=True)


asyncio.run(main())
print("asyncio.run returned", flush=True)
"""


@pytest.mark.parametrize("caught", [True, False], ids=["caught", "not-caught"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
def test_a_script_that_catches_the_cancellation_around_the_robot_ends_normally(
    tmp_path: Path, signum: signal.Signals, caught: bool
) -> None:
    # asyncio.run's rule at the main task's end, not at the block's: KeyboardInterrupt
    # (SystemExit(143)) only if the cancellation ended the task. Before: caught around
    # `async with Robot()`, it still ended in KeyboardInterrupt (exit 130) or 143.
    script = tmp_path / "around.py"
    script.write_text(AROUND, encoding="utf-8")
    command = [sys.executable, str(script), "caught" if caught else "not"]
    with started(command, stdout=PIPE, stderr=PIPE) as child:
        assert child.stdout is not None
        assert child.stdout.readline() == "ready\n"
        child.send_signal(signum)
        out, err = child.communicate(timeout=HANG_GUARD)
    again = "Ctrl-C" if signum == signal.SIGINT else signum.name
    said = f"{signum.name}: stopping the robot ({again} again stops at once)\n"
    if caught:
        assert (child.returncode, out, err) == (
            0,
            "cleaned up around the robot\nafter the robot\nasyncio.run returned\n",
            said,
        )
    elif signum == signal.SIGINT:  # Python's own ending: it re-raises SIGINT, after a traceback
        assert (child.returncode, out) == (-signal.SIGINT, "")
        assert err.startswith(said)
        assert err.endswith("\nKeyboardInterrupt\n")
    else:
        assert (child.returncode, out, err) == (143, "", said)


RECORDED = """
import asyncio
import sys

from pyrobots_aio import Robot, action
from pyrobots_aio.recording import JsonlRecorder

PATH, POINT = sys.argv[1:]


def at(point):
    # Says where the program is; waits (blocked) for the parent's line if told to.
    print(point, flush=True)
    if point == POINT == "closing":
        sys.stdin.readline()


class Recorder(JsonlRecorder):
    def close(self):
        at("closing")  # after `async with robot` has left: the robot has stopped
        super().close()


@action
async def hold(robot):
    try:
        await asyncio.sleep(3600)
    except asyncio.CancelledError:
        at("cleaning")  # the robot's exit: its actions' cleanup
        if POINT == "cleaning":
            await asyncio.sleep(3600)  # (a second signal cuts it short)
        raise


async def main():
    robot = Robot(actions=[hold], cancel_grace=3600)
    with Recorder(PATH).attach(robot):
        async with robot:
            print("ready", flush=True)
            await robot.hold()


asyncio.run(main())
"""


@pytest.mark.parametrize("point", ["cleaning", "closing"])
def test_a_second_sigterm_during_the_shutdown_leaves_the_recording_whole(
    tmp_path: Path, point: str
) -> None:
    # The README's pattern. Before: the robot gave SIGTERM back to Python's default as
    # it left, and a second one during the recorder's close ended the process there
    # (exit -15), the recording cut short, without its end record.
    script, path = tmp_path / "recorded.py", tmp_path / "run.jsonl"
    script.write_text(RECORDED, encoding="utf-8")
    command = [sys.executable, str(script), str(path), point]
    with started(command, stdin=PIPE, stdout=PIPE, stderr=PIPE) as child:
        assert child.stdout is not None
        assert child.stdout.readline() == "ready\n"
        child.send_signal(signal.SIGTERM)
        while (line := child.stdout.readline()) not in {f"{point}\n", ""}:
            pass  # ("cleaning" comes before "closing")
        assert line == f"{point}\n"
        child.send_signal(signal.SIGTERM)  # the first was delivered: the program reacted
        wait_delivered(child, signal.SIGTERM)
        _, err = child.communicate("go on\n", timeout=HANG_GUARD)
    assert child.returncode == 143, err
    assert "SIGTERM again: stopping at once, cutting the cleanup short\n" in err
    assert path.read_bytes().endswith(b"\n")
    recording = load(path)
    assert recording.complete  # its end record is there
    [finished] = [e for e in recording.events if e.kind is EventKind.ACTION_FINISHED]
    assert (finished.name, finished.data["outcome"]) == ("hold", "cancelled")
