"""Moving averages behind `StateStore.filtered` (pyRobots' ``robot.filtered``)."""

from __future__ import annotations

import math
from collections import deque

from .._core._numbers import finite, shown

MAX_WINDOW = 1_000_000
"""The most values a moving window holds (over 16 minutes of a 1 kHz sensor)."""


def check_window(window: int) -> None:
    """Raise ValueError unless ``window`` is an integer from 1 to `MAX_WINDOW`."""
    if isinstance(window, bool) or not isinstance(window, int) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")
    if window > MAX_WINDOW:
        raise ValueError(f"window must be at most {MAX_WINDOW:,} values, got {shown(window)}")


class MovingAverage:
    """The mean of the last ``window`` values added.

    Examples:
        >>> average = MovingAverage(3)
        >>> [average.add(v) for v in (3.0, 6.0, 9.0, 12.0)]
        [3.0, 4.5, 6.0, 9.0]
    """

    __slots__ = ("_values", "_window")

    def __init__(self, window: int) -> None:
        check_window(window)
        self._window = window
        self._values: deque[float] = deque(maxlen=window)

    @property
    def window(self) -> int:
        """How many of the latest values the mean covers."""
        return self._window

    def add(self, value: float) -> float:
        """Add ``value`` and return the mean of the window (fewer values at first).

        Raises:
            ValueError: ``value`` is not a finite number (a NaN would spoil the
                mean for the next ``window`` values; skip NaN readings instead).
        """
        self._values.append(
            finite("a filtered value", value, fix="skip readings that are NaN or infinite")
        )
        return math.fsum(self._values) / len(self._values)

    def resize(self, window: int) -> None:
        """Change the window, keeping the latest values that still fit."""
        check_window(window)
        self._window = window
        self._values = deque(self._values, maxlen=window)

    def __repr__(self) -> str:
        return f"<MovingAverage window={self.window} values={list(self._values)!r}>"
