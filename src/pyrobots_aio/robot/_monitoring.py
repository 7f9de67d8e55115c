"""The robot's state-facing methods (pyRobots vocabulary), kept apart from the executive."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..state import StateStore


class StateMethods:
    """Methods of `Robot` that read or watch ``robot.state``."""

    state: StateStore

    def filtered(self, name: str, value: float, window: int = 10) -> float:
        """Add ``value`` to the moving window ``name`` and return the window's mean.

        pyRobots' ``robot.filtered``: smooth a noisy reading before acting on it.

        Example:
            >>> from pyrobots_aio import Robot
            >>> robot = Robot()
            >>> robot.filtered("sonar", 1.0), robot.filtered("sonar", 2.0)
            (1.0, 1.5)
        """
        return self.state.filtered(name, value, window)
