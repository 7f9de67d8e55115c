"""Ctrl-C and SIGTERM, sent for real to real processes, many times over, with varied gaps.

A real-time robot spends most of its time waiting for the next control tick, so
a signal that lands at a bad moment is rare in any one run: each test runs the
program many times (a few at once, which also varies the timing), signals it
after a random delay, and a second time after a random gap of 0 to 300 ms (and
not before the first was delivered: two pending signals of one kind merge). The
processes get a generous hang guard: the point is that they end at all. That a
second signal cut a cleanup short is read from the recording, in the loop's
own time; and each test's pytest timeout is the sum of the hang guards of the
runs it makes, so that a loaded machine makes it slower, never failed.
"""

from __future__ import annotations

import math
import random
import re
import signal
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EventKind
from pyrobots_aio.recording import load
from signal_support import HANG_GUARD, STARTUP_GUARD, first_line, wait_delivered

if TYPE_CHECKING:
    from collections.abc import Sequence

    from pyrobots_aio.recording import Recording

DEMO = [sys.executable, "-m", "pyrobots_aio.cli", "demo", "random-walk", "--realtime", "-v"]
AT_ONCE = 4
"""Processes run side by side."""
DELAY, GAP = 0.5, 0.3
"""The longest wait before the first signal, and between the first and the second."""
RUN_BOUND = STARTUP_GUARD + DELAY + GAP + 2 * HANG_GUARD  # its first line, waits, ending
CLEANUP = 30.0
"""Seconds (of the loop's clock) the scripts' cleanup lasts unless a second signal cuts it."""


def runs_guard(runs: int, at_once: int = AT_ONCE) -> pytest.MarkDecorator:
    """A pytest timeout for ``runs`` signalled runs, ``at_once`` at a time: their bounds added.

    The suite's default (120 s) is a hang guard for one test's own work; these
    tests start a process per run, and a loaded machine slows each start and
    ending several times over (20 runs one after another took more than 120 s
    beside a CPU hog on each core).
    """
    return pytest.mark.timeout(math.ceil(runs / at_once) * RUN_BOUND)


SCRIPT = f"""
import asyncio
import contextlib
import sys

from pyrobots_aio import ActionCancelled, action
from pyrobots_aio.cli import stop_on_signals
from pyrobots_aio.recording import JsonlRecorder
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk


@action
async def blink(robot):
    await asyncio.sleep(0)


@action
async def walk(robot):
    try:
        await random_walk(robot, moves=100)
    except ActionCancelled:
        # A long and busy cleanup: short actions one after another for {CLEANUP:g} s (the
        # loop is never idle, so a signal lands in the middle of things), bounded by
        # cancel_grace=120 only; a second signal must cut it short.
        end = robot.time() + {CLEANUP}
        while robot.time() < end:
            await blink(robot)
        raise


async def main(path, guarded):
    robot = SimRobot(realtime=True, cancel_grace=120)
    guard = stop_on_signals() if guarded else contextlib.nullcontext()
    recorder = JsonlRecorder(path, state_keys=("bumper", "v", "w"), sample_rate=None)
    with guard, recorder.attach(robot):
        async with robot:
            print("ready", flush=True)
            await walk(robot)


asyncio.run(main(sys.argv[2], sys.argv[1] == "guarded"))
"""


@dataclass(frozen=True, repr=False)
class Run:
    """One signalled run: what the process did and what it left."""

    signals: tuple[signal.Signals, ...]
    delay: float
    gap: float
    returncode: int | None  # None: still running at the hang guard (then killed)
    stdout: str
    stderr: str
    path: Path

    def __repr__(self) -> str:
        sent = "+".join(s.name for s in self.signals)
        return (
            f"{sent} after {self.delay:.3f} s, gap {self.gap:.3f} s: exit {self.returncode}\n"
            f"--- stderr ---\n{self.stderr[-3000:]}"
        )


def _signalled(
    command: Sequence[str], path: Path, signals: Sequence[signal.Signals], rng: random.Random
) -> Run:
    """Start ``command``, wait for its first line, send ``signals`` with random delays."""
    delay, gap = rng.uniform(0.0, DELAY), rng.uniform(0.0, GAP)
    with subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    ) as child:
        first = first_line(child)  # the robot runs
        waits = [delay] + [gap] * (len(signals) - 1)
        sent: signal.Signals | None = None
        for wait, signum in zip(waits, signals, strict=True):
            try:
                child.wait(timeout=wait)  # a pause, unless it ended already
            except subprocess.TimeoutExpired:
                if sent is not None:
                    wait_delivered(child, sent)
                child.send_signal(signum)
                sent = signum
        try:
            out, err = child.communicate(timeout=HANG_GUARD)
            code: int | None = child.returncode
        except subprocess.TimeoutExpired:
            child.kill()
            out, err = child.communicate()
            code = None
    return Run(tuple(signals), delay, gap, code, first + out, err, path)


def _many(
    tmp_path: Path,
    command: Sequence[str],
    signals: Sequence[signal.Signals],
    tries: int,
    seed: int,
) -> list[Run]:
    tmp_path.mkdir(exist_ok=True)
    rng = random.Random(seed)
    plans = [(tmp_path / f"run{i}.jsonl", random.Random(rng.random())) for i in range(tries)]
    with ThreadPoolExecutor(AT_ONCE) as pool:
        runs = pool.map(
            lambda plan: _signalled([*command, str(plan[0])], plan[0], signals, plan[1]), plans
        )
        return list(runs)


def _check_recording(run: Run) -> Recording:
    """The recording is closed and valid, and was closed after the robot's shutdown."""
    assert run.path.read_bytes().endswith(b"\n"), run
    recording = load(run.path)  # strict: every line reads
    assert recording.complete, run  # its end record is there
    spawned = {e.action for e in recording.events if e.kind is EventKind.ACTION_SPAWNED}
    finished = {e.action for e in recording.events if e.kind is EventKind.ACTION_FINISHED}
    assert spawned == finished, f"actions never finished: {spawned - finished}; {run}"
    return recording


def _check_cut_short(recording: Recording, run: Run) -> None:
    """The walk ended before its cleanup would have ended by itself: the second signal cut it."""
    walk = [e for e in recording.events if e.name == "walk"]
    cancelled = next(e.time for e in walk if e.kind is EventKind.CANCEL_REQUESTED)
    [finished] = [e.time for e in walk if e.kind is EventKind.ACTION_FINISHED]
    assert finished - cancelled < CLEANUP, run


@runs_guard(40)
def test_a_second_ctrl_c_ends_the_demo_with_its_recording_closed(tmp_path: Path) -> None:
    # Before: a second Ctrl-C raised KeyboardInterrupt wherever it landed, and the exit
    # code depended on where (130, or -2 when it came during the interpreter's exit).
    runs = _many(tmp_path, [*DEMO, "--record"], [signal.SIGINT] * 2, tries=40, seed=11)
    for run in runs:
        assert run.returncode == 130, run
        assert run.stderr.endswith("pyrobots-aio: interrupted\n"), run
        assert "Traceback" not in run.stderr, run
        _check_recording(run)


@runs_guard(6 + 6)
def test_sigterm_stops_the_demo_in_order_and_exits_143(tmp_path: Path) -> None:
    # Before: SIGTERM killed the process at once: no cleanup, no end record, and up to
    # 1 s of events lost in the recorder's buffer.
    once = _many(tmp_path / "once", [*DEMO, "--record"], [signal.SIGTERM], tries=6, seed=12)
    twice = _many(tmp_path / "twice", [*DEMO, "--record"], [signal.SIGTERM] * 2, tries=6, seed=13)
    for run in once + twice:
        assert run.returncode == 143, run
        assert run.stderr.endswith("pyrobots-aio: terminated\n"), run
        recording = _check_recording(run)
        # The motion under way was cancelled (its cleanup stopped the wheels), not cut off.
        outcomes = [
            e.data["outcome"] for e in recording.events if e.kind.value == "action.finished"
        ]
        assert outcomes[-1] == "cancelled", run
        # The warning's time is since the robot's start, as the event lines' are (not the
        # loop's raw clock, seconds since boot): within the recording.
        found = re.search(
            r"^ *(\d+\.\d{3})  WARNING signals  SIGTERM: stopping the robot",
            run.stderr,
            re.MULTILINE,
        )
        assert found is not None, run
        assert 0.0 <= float(found.group(1)) <= recording.duration, run


@runs_guard(16)
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=lambda s: s.name)
@pytest.mark.parametrize("mode", ["guarded", "plain"])
def test_a_second_signal_cuts_a_scripts_cleanup_short(
    tmp_path: Path, signum: signal.Signals, mode: str
) -> None:
    # "plain": no stop_on_signals, the robot's own handling (Robot(handle_signals=True)).
    script = tmp_path / "walk.py"
    script.write_text(SCRIPT, encoding="utf-8")
    command = [sys.executable, str(script)]
    tries = 16 if mode == "guarded" else 8
    runs = _many(tmp_path, [*command, mode], [signum] * 2, tries=tries, seed=int(signum))
    for run in runs:
        # Python's own ending for each: KeyboardInterrupt re-raises SIGINT; SystemExit(143).
        assert run.returncode == (-signal.SIGINT if signum == signal.SIGINT else 143), run
        again = "Ctrl-C" if signum == signal.SIGINT else signum.name
        assert f"{signum.name}: stopping the robot ({again} again stops at once)\n" in run.stderr
        assert f"{signum.name} again: stopping at once, cutting the cleanup short\n" in run.stderr
        recording = _check_recording(run)
        walk = [
            e for e in recording.events if e.name == "walk" and e.kind.value == "action.finished"
        ]
        assert [e.data["outcome"] for e in walk] == ["cancelled"], run
        _check_cut_short(recording, run)


@runs_guard(20, at_once=1)
def test_a_second_ctrl_c_ends_a_plain_asyncio_run_script(tmp_path: Path) -> None:
    script = tmp_path / "walk.py"
    script.write_text(SCRIPT, encoding="utf-8")
    rng = random.Random(14)
    for i in range(20):  # fails at the first bad run: usually the first
        path = tmp_path / f"run{i}.jsonl"
        run = _signalled(
            [sys.executable, str(script), "plain", str(path)], path, [signal.SIGINT] * 2, rng
        )
        assert run.returncode == -signal.SIGINT, run
        _check_cut_short(_check_recording(run), run)


def test_stop_on_signals_leaves_signals_the_program_handles_alone(tmp_path: Path) -> None:
    program = tmp_path / "own.py"
    program.write_text(
        "import asyncio, signal\n"
        "from pyrobots_aio.cli import stop_on_signals\n"
        "signal.signal(signal.SIGTERM, lambda *_: None)\n"
        "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
        "async def main():\n"
        "    with stop_on_signals() as stopping:\n"
        "        print(stopping.handled, flush=True)\n"
        "    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN\n"
        "asyncio.run(main())\n",
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, str(program)], capture_output=True, text=True, timeout=60, check=False
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "()\n", "")


def test_stop_on_signals_restores_asyncio_runs_handler(tmp_path: Path) -> None:
    program = tmp_path / "restore.py"
    program.write_text(
        "import asyncio, signal\n"
        "from pyrobots_aio.cli import stop_on_signals\n"
        "async def main():\n"
        "    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)\n"
        "    with stop_on_signals() as stopping:\n"
        "        print([s.name for s in stopping.handled], flush=True)\n"
        "    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before\n"
        "asyncio.run(main())\n",
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, str(program)], capture_output=True, text=True, timeout=60, check=False
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "['SIGINT', 'SIGTERM']\n", "")


def test_off_the_main_thread_stop_on_signals_does_nothing(tmp_path: Path) -> None:
    program = tmp_path / "thread.py"
    program.write_text(
        "import asyncio, threading\n"
        "from pyrobots_aio.cli import stop_on_signals\n"
        "async def main():\n"
        "    with stop_on_signals() as stopping:\n"
        "        return stopping.handled\n"
        "found = []\n"
        "thread = threading.Thread(target=lambda: found.append(asyncio.run(main())))\n"
        "thread.start(); thread.join()\n"
        "print(found, flush=True)\n",
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, str(program)], capture_output=True, text=True, timeout=60, check=False
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "[()]\n", "")
