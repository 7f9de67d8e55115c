"""`Refusals`: a burst of refused messages logged as one story, not one traceback per message.

A flood of bad commands (NaN ``cmd_vel`` at 10 kHz) once wrote thousands of
tracebacks a second. A burst now makes two lines: the first refusal, at once
(what came, and what the node did), and, once the burst is over (``gap``
seconds of the loop's clock without one), how many were refused and for how
long. The end is found by one timer per burst, re-armed to the last
refusal's time when it fires early: nothing runs per refused message but a
count.
"""

from __future__ import annotations

import asyncio
import logging

_log = logging.getLogger("pyrobots_aio.cli")

BURST_GAP = 1.0
"""Seconds without a refusal that end a burst."""


class Refusals:
    """Counts the refusals of one input (``cmd_vel``), logging each burst's start and end.

    Args:
        what: The input, as the log lines name it.
        gap: Seconds without a refusal that end a burst.
    """

    def __init__(self, what: str, gap: float = BURST_GAP) -> None:
        self.what, self.gap = what, gap
        self.count = 0
        """Refusals in the current burst (0: no burst)."""
        self._first = self._last = 0.0
        self._timer: asyncio.TimerHandle | None = None

    def refuse(self, why: str) -> None:
        """Count one refusal (on the loop); the first of a burst is logged with ``why``."""
        loop = asyncio.get_running_loop()
        self._last = now = loop.time()
        if self.count == 0:
            self._first = now
            _log.warning(
                "%s: %s; counting the refusals until %g s pass without one",
                self.what,
                why,
                self.gap,
            )
            self._timer = loop.call_at(now + self.gap, self._check)
        self.count += 1

    def _check(self) -> None:
        loop = asyncio.get_running_loop()
        end = self._last + self.gap
        if loop.time() < end:
            self._timer = loop.call_at(end, self._check)
            return
        _log.warning(
            "%s: the burst is over: %d refused in %.1f s",
            self.what,
            self.count,
            self._last - self._first,
        )
        self.count, self._timer = 0, None

    def close(self) -> None:
        """Stop watching (a burst still open is not reported)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
