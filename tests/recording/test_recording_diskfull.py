"""A recording that runs out of room: a real full disk (a 64 KiB tmpfs) and a real file-size limit.

Either way the write fails with an OSError in the middle of the run. The robot
must run on, the recorder must say so once, leave a file that ends on a whole
line and reads back, and fail loudly when closed; the demo must exit non-zero
without a traceback.
"""

from __future__ import annotations

import contextlib
import logging
import re
import subprocess
import sys
from typing import TYPE_CHECKING

import pytest

from log_support import logged, without_watchdog
from pyrobots_aio import EventKind, RecordingError, Robot, action
from pyrobots_aio.recording import JsonlRecorder, load

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

SMALL = 64 * 1024
"""Bytes of room: a few hundred events."""
DEMO = [sys.executable, "-m", "pyrobots_aio.cli", "-q", "demo", "random-walk", "--duration", "600"]


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A directory on a 64 KiB tmpfs mounted for the test (needs root; skipped otherwise).

    Without root, `test_a_file_size_limit_stops_the_demo_cleanly` runs the same
    failing-write path through a file-size limit.
    """
    where = tmp_path / "small"
    where.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={SMALL}", "tmpfs", str(where)],
        capture_output=True,
        text=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {mounted.stderr.strip()}")
    try:
        yield where
    finally:  # lazily if a file on it is still open: never leave the mount behind
        subprocess.run(["umount", "--lazy", str(where)], check=True)


@action
async def blink(robot: Robot) -> None:
    await robot.sleep(0.01)


async def _blinks(robot: Robot, count: int) -> int:
    done = 0
    for _ in range(count):
        await blink(robot)
        done += 1
    return done


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_full_disk_stops_the_recording_not_the_robot(
    small_disk: Path, caplog: pytest.LogCaptureFixture
) -> None:
    path = small_disk / "run.jsonl"
    recorder = JsonlRecorder(path, buffer_size=50)
    robot = Robot()
    with pytest.raises(RecordingError) as failed, recorder.attach(robot):
        async with robot:
            assert await _blinks(robot, 2000) == 2000  # the robot ran on
    assert str(failed.value) == (
        f"recording to {path} failed: [Errno 28] No space left on device; the file keeps "
        "the events written before, up to its last whole line, without an end record"
    )
    assert isinstance(recorder.error, OSError)
    warnings = logged(caplog, logging.WARNING)
    assert [(r.name, r.levelname, r.getMessage()) for r in warnings] == [
        (
            "pyrobots_aio.recording",
            "WARNING",
            f"recording to {path} stopped: [Errno 28] No space left on device; the file keeps "
            "what was written before, up to its last whole line, and the robot runs on "
            "unrecorded",
        )
    ]
    data = path.read_bytes()
    assert data.endswith(b"\n")
    recording = load(path)  # strict: every line reads
    assert not recording.complete  # no end record: the file says it was cut
    assert 100 < len(recording.events) < 2000 * 3
    kinds = {e.kind for e in recording.events}
    assert kinds == {EventKind.ACTION_SPAWNED, EventKind.ACTION_STARTED, EventKind.ACTION_FINISHED}
    assert repr(recorder).startswith(f"<JsonlRecorder {str(path)!r} failed, ")


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_disk_that_fills_before_close_fails_the_close(
    small_disk: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # The events wait in the buffer (no write until close), and meanwhile something else
    # fills the disk: the final write fails, and close says so.
    path = small_disk / "run.jsonl"
    recorder = JsonlRecorder(path, buffer_size=10_000, flush_interval=3600)
    robot = Robot()
    with pytest.raises(RecordingError), recorder.attach(robot):  # noqa: PT012
        _fill(small_disk / "filler")
        async with robot:
            await _blinks(robot, 50)
    assert path.read_bytes().endswith(b"\n")
    assert not load(path).complete
    assert sum(r.levelno == logging.WARNING for r in logged(caplog)) == 1


def _fill(path: Path) -> None:
    """Write to ``path`` until the disk is full."""
    with path.open("wb", buffering=0) as filler, contextlib.suppress(OSError):
        while filler.write(b"x" * 4096):
            pass


def test_the_demo_on_a_full_disk_warns_once_and_exits_1(small_disk: Path) -> None:
    path = small_disk / "walk.jsonl"
    done = subprocess.run(
        [*DEMO, "--record", str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    _check_the_demo_failed(done, path, "[Errno 28] No space left on device")


def test_a_file_size_limit_stops_the_demo_cleanly(tmp_path: Path) -> None:
    # The same failing write without root: RLIMIT_FSIZE makes write() fail with EFBIG
    # (SIGXFSZ, which would kill the process instead, is ignored as a shell's ulimit -f
    # users do).
    path = tmp_path / "walk.jsonl"
    program = (
        "import resource, signal, sys\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({SMALL}, {SMALL}))\n"
        "from pyrobots_aio.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", program, *DEMO[3:], "--record", str(path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    _check_the_demo_failed(done, path, "[Errno 27] File too large")
    assert path.stat().st_size <= SMALL


def _check_the_demo_failed(done: subprocess.CompletedProcess[str], path: Path, why: str) -> None:
    assert done.returncode == 1, done.stderr
    lines = without_watchdog(done.stderr)
    assert "Traceback" not in done.stderr
    assert len(lines) == 2, done.stderr
    warning = (
        f"recording to {path} stopped: {why}; the file keeps what was written before, up to "
        "its last whole line, and the robot runs on unrecorded"
    )
    # time since start, level, logger, the action whose event filled the disk, the message
    assert re.fullmatch(
        rf" +\d+\.\d{{3}}  WARNING recording(  \w+#\d+)?  {re.escape(warning)}", lines[0]
    )
    assert lines[1] == (
        f"pyrobots-aio: error: recording to {path} failed: {why}; the file keeps the events "
        "written before, up to its last whole line, without an end record"
    )
    assert path.read_bytes().endswith(b"\n")
    recording = load(path)
    assert not recording.complete
    assert recording.events  # what was written before the disk filled is there


def test_the_watchdog_s_reports_are_left_out_of_the_lines_checked() -> None:
    # As the demo prints them: the WARNING comes from the watchdog's thread, where no
    # loop runs, so its time column is blank (a loaded machine failed the demo tests
    # with 130 and 44 lines: the filter took these records for the lines before them).
    stderr = (
        "           WARNING watchdog  the event loop has not turned for 0.121 s: a callback"
        " blocks it at _world.py:293. The blocking stack (most recent call last):\n"
        '  File "/x/_world.py", line 293, in step\n'
        "    mujoco.mj_step(model, data, nstep=rest)\n"
        "    3.990  INFO    watchdog  the event loop turned again after 0.125 s\n"
        "    4.000  WARNING recording  walk#3  recording to x stopped\n"
        "           WARNING watchdog  the event loop has not turned for 0.102 s: a callback"
        " blocks it at _world.py:322. The blocking stack (most recent call last):\n"
        '  File "/x/_world.py", line 322, in step\n'
        "    mujoco.mj_step(model, data, nstep=rest)\n"
        "pyrobots-aio: error: recording to x failed\n"
    )
    assert without_watchdog(stderr) == [
        "    4.000  WARNING recording  walk#3  recording to x stopped",
        "pyrobots-aio: error: recording to x failed",
    ]
