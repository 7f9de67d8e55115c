"""Moving averages behind `StateStore.filtered` (pyRobots' ``robot.filtered``)."""

from __future__ import annotations

import math
from collections import deque


def check_window(window: int) -> None:
    """Raise ValueError unless ``window`` is a positive integer."""
    if isinstance(window, bool) or not isinstance(window, int) or window < 1:
        raise ValueError(f"window must be a positive integer, got {window!r}")


class MovingAverage:
    """The mean of the last ``window`` values added.

    Example:
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
        """Add ``value`` and return the mean of the window (fewer values at first)."""
        self._values.append(value)
        return math.fsum(self._values) / len(self._values)

    def resize(self, window: int) -> None:
        """Change the window, keeping the latest values that still fit."""
        check_window(window)
        self._window = window
        self._values = deque(self._values, maxlen=window)

    def __repr__(self) -> str:
        return f"<MovingAverage window={self.window} values={list(self._values)!r}>"
