"""Sending real signals to real processes, one at a time (shared by the signal tests)."""

from __future__ import annotations

import contextlib
import subprocess
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import signal
    from collections.abc import Iterator, Sequence

HANG_GUARD = 15.0
"""Seconds a signalled process gets to end: far more than an orderly stop takes, and less
than the 30 s cleanup of the scripts in tests/cli/test_cli_signals.py, which a second signal
must cut short."""


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
