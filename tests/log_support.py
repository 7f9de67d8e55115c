"""What the code under test logged, the loop watchdog's records left out.

The watchdog reports a loop that did not turn for its threshold (0.1 s): on a
loaded machine the code a test runs (a ``gc.collect()``, a physics step) takes
that long now and then, and the watchdog rightly says so. That report is about
the machine, not about what these tests check. The watchdog stays on in them,
as in every robot; its own tests read its logger directly
(tests/core/test_blockwatch.py, tests/robot/test_robot_watchdog.py).
"""

from __future__ import annotations

import logging
import re

import pytest

WATCHDOG = "pyrobots_aio.watchdog"
"""The loop watchdog's logger (DESIGN.md §13)."""


def logged(
    caplog: pytest.LogCaptureFixture, level: int = logging.NOTSET
) -> list[logging.LogRecord]:
    """``caplog``'s records at ``level`` and above, but the loop watchdog's."""
    return [r for r in caplog.records if r.levelno >= level and r.name != WATCHDOG]


_RECORD = re.compile(r" *(?:\d+\.\d{3})?  [A-Z]+ +(\S+)")
"""The first line of a console log record (`pyrobots_aio.cli.ConsoleHandler`): time since
start, level, logger.

The time is blank for a record logged off the loop's thread: the watchdog's WARNING
(the INFO when the loop turns again is logged on the loop, with its time).
"""


def without_watchdog(output: str) -> list[str]:
    """The lines of a program's console log but the loop watchdog's records (with their stack).

    A record goes on over the indented lines that follow it; any other line (a record,
    or a line the program printed) ends it.
    """
    kept: list[str] = []
    dropping = False
    for line in output.splitlines():
        start = _RECORD.match(line)
        if start is not None:
            dropping = start.group(1) == "watchdog"
        elif not line.startswith("  "):
            dropping = False
        if not dropping:
            kept.append(line)
    return kept
