"""Sending real signals to real processes, one at a time (shared by the signal tests)."""

from __future__ import annotations

import contextlib
import select
import subprocess
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import signal
    from collections.abc import Iterator, Sequence

HANG_GUARD = 60.0
"""Seconds a signalled process gets to end: a deadlock guard, not a measure of speed.

An orderly stop takes 0.3 s on a quiet machine and 2 to 3 s with four at once beside a
CPU hog on each core (load 17): the guard leaves room for a machine twice as loaded and
then some. It is longer than the 30 s cleanup of the scripts in
tests/cli/test_cli_signals.py, so a second signal that fails to cut one short shows in
the recording (the loop's own clock), not as a race against this wall clock."""
STARTUP_GUARD = 60.0
"""Seconds a process gets to print its first line: importing MuJoCo took 11 s at load 30."""


def first_line(child: subprocess.Popen[str]) -> str:
    """The first line ``child`` prints, waited for at most `STARTUP_GUARD` seconds."""
    assert child.stdout is not None
    ready, _, _ = select.select([child.stdout], [], [], STARTUP_GUARD)
    assert ready, f"no line from {child.args} in {STARTUP_GUARD:g} s"
    return child.stdout.readline()


def wait_delivered(child: subprocess.Popen[str], signum: signal.Signals) -> None:
    """Wait until ``signum`` sent to ``child`` is no longer pending in the kernel.

    Signals of one kind do not queue: a second one sent while the first is
    still pending (its process not scheduled yet, on a loaded machine) merges
    with it, and the process sees one. So a second signal is sent only once
    the first was delivered, whatever the gap.
    """
    bit = 1 << (signum - 1)
    deadline = time.monotonic() + HANG_GUARD
    while time.monotonic() < deadline and child.poll() is None:
        try:
            masks = [
                int(line.split()[1], 16)
                for status in Path(f"/proc/{child.pid}/task").glob("*/status")
                for line in status.read_text().splitlines()
                if line.startswith(("SigPnd:", "ShdPnd:"))
            ]
        except OSError:  # it is ending
            return
        if not any(mask & bit for mask in masks):
            return
        time.sleep(0.001)


@contextlib.contextmanager
def started(command: Sequence[str], **options: Any) -> Iterator[subprocess.Popen[str]]:
    """Run ``command`` (text pipes as ``options`` say); kill it if it still runs at the end."""
    with subprocess.Popen(command, text=True, **options) as child:
        try:
            yield child
        finally:
            if child.poll() is None:  # a failed test: do not wait for it
                child.kill()
