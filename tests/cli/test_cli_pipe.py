"""``pyrobots-aio ... | head``: a reader that goes away ends the command quietly (exit 141)."""

from __future__ import annotations

import os
import subprocess
import sys
from typing import TYPE_CHECKING

from pyrobots_aio.recording import load

if TYPE_CHECKING:
    from pathlib import Path

CLI = [sys.executable, "-m", "pyrobots_aio.cli"]


def _into_a_closed_pipe(args: list[str]) -> subprocess.CompletedProcess[bytes]:
    """Run the command with its standard output a pipe whose reader is already gone."""
    reader, writer = os.pipe()
    os.close(reader)  # as `head` does once it has its lines
    try:
        return subprocess.run(
            [*CLI, *args], stdout=writer, stderr=subprocess.PIPE, timeout=300, check=False
        )
    finally:
        os.close(writer)


def test_replay_into_a_closed_pipe_exits_quietly(recording: Path) -> None:
    # Before: "pyrobots-aio: error: [Errno 32] Broken pipe", exit 1.
    done = _into_a_closed_pipe(["replay", str(recording)])
    assert (done.returncode, done.stderr) == (141, b"")


def test_the_demo_into_a_closed_pipe_stops_in_order_and_quietly(tmp_path: Path) -> None:
    # Before: a logged traceback per event line ("instrument ... failed"), the run going
    # on unseen to its end, then "[Errno 32] Broken pipe".
    path = tmp_path / "walk.jsonl"
    done = _into_a_closed_pipe(["demo", "random-walk", "-v", "--record", str(path)])
    assert (done.returncode, done.stderr) == (141, b"")
    recording = load(path)
    assert recording.complete  # stopped at its first line, and closed in order
    outcomes = [e.data["outcome"] for e in recording.events if e.kind.value == "action.finished"]
    assert outcomes == ["cancelled", "cancelled"]  # undock and its drive, not run to their end


def test_the_demo_stops_at_its_first_progress_line_into_a_closed_pipe(tmp_path: Path) -> None:
    path = tmp_path / "walk.jsonl"
    done = _into_a_closed_pipe(["demo", "random-walk", "--record", str(path)])
    assert (done.returncode, done.stderr) == (141, b"")
    recording = load(path)
    assert recording.complete
    assert recording.duration < 10.1  # the first progress line comes at 10 s
