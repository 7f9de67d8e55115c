"""How the supervisors take part in the emergency stop: a `StopWatch` while they run.

``robot.emergency_stop`` cancels the resource holders; a supervised plan may
hold nothing (a ``retry`` waiting out its backoff, a ``StateMachine`` state
that only thinks), so each supervisor hands the stop what it runs, through
``robot.add_emergency_stop_callback``, and learns that a stop came.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Self

if TYPE_CHECKING:
    from ..actions import ActionHandle
    from ..robot import Robot


class StopWatch:
    """While entered, each emergency stop also cancels ``target``, and is noted in ``reason``.

    `retry` watches with its retrying action as the target, a `StateMachine`
    with each state's action in turn.

    Attributes:
        target: The action the stop is to cancel too (None: none).
        reason: The reason of the last stop called while entered, or None.
    """

    __slots__ = ("_robot", "reason", "target")

    def __init__(self, robot: Robot, target: ActionHandle[Any] | None) -> None:
        self._robot = robot
        self.target = target
        self.reason: str | None = None

    def __enter__(self) -> Self:
        self._robot.add_emergency_stop_callback(self._stopped)
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._robot.remove_emergency_stop_callback(self._stopped)

    def _stopped(self, reason: str) -> tuple[ActionHandle[Any], ...]:
        self.reason = reason
        return () if self.target is None else (self.target,)
