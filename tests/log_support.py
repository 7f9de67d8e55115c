"""What the code under test logged: pytest's ``caplog`` records, the loop watchdog's left out."""

from __future__ import annotations

import logging

import pytest

WATCHDOG = "pyrobots_aio.watchdog"
"""The loop watchdog's logger (DESIGN.md §13)."""


def logged(
    caplog: pytest.LogCaptureFixture, level: int = logging.NOTSET
) -> list[logging.LogRecord]:
    """``caplog``'s records at ``level`` and above, but the loop watchdog's.

    The watchdog reports a loop that did not turn for its threshold (0.1 s): on a
    loaded machine the test's own code (a ``gc.collect()``, a physics step) takes
    that long now and then, and the watchdog rightly says so. That report is about
    the machine, not about what these tests check. The watchdog stays on in them, as
    in every robot; its own tests read its logger directly (tests/core/test_blockwatch.py,
    tests/robot/test_robot_watchdog.py).
    """
    return [r for r in caplog.records if r.levelno >= level and r.name != WATCHDOG]
