"""Stall detection: a motion that commands the wheels and sees its odometry go nowhere ends.

A real base's firmware notices stalled wheels (the Create 3 does); a motion
action that pushed on without noticing would drive into a wall for ever. So
every motion action watches its own odometry against its own commands, tick by
tick (`StallWatch`), and fails with a `StallError` (a `MotionError`) once it
has commanded motion for the base's ``stall_timeout`` seconds (`STALL_TIMEOUT`
by default) without progress. *Progress* is odometry that moved `STALL_TRAVEL`
metres or turned `STALL_TURN` radians (or, for a slower command, a quarter of
what was commanded) since the last progress; a robot that creeps along a wall
at a hundredth of its command makes none. Only the commanded parts count (a
drive that only turns, pushed aside, makes no progress).

The time is counted in control ticks (each the base's ``control_period``), the
sensor updates the motion sees: odometry that comes late, in a burst (a ROS 2
base on a loaded machine), is not taken for a stall, and time frozen (a
pause, a suspension that lends the wheels) does not count.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from .._exceptions import StallError
from ._math import wrap_angle

if TYPE_CHECKING:
    from ..actions import ActionHandle
    from ._base import DriveBase

STALL_TIMEOUT = 1.5
"""Seconds a motion action may command motion without progress (`DriveBase.stall_timeout`).

Long enough for a base to get going from rest or to reverse (the simulator's
random walks never go 0.1 s without progress), short enough that a blocked
robot gives up before its motors heat.
"""
STALL_TRAVEL = 0.01
"""Metres of odometry that count as progress for a command to drive."""
STALL_TURN = 0.05
"""Radians of odometry that count as progress for a command to turn."""
_SHARE = 0.25  # of a command slower than STALL_TRAVEL or STALL_TURN per stall_timeout
_SLACK = 1e-9  # seconds: a sum of tick periods lands a hair short of a round number

Velocity = tuple[float, float]
"""A wheel command ``(v, w)``, in m/s and rad/s."""


class StallWatch:
    """One motion's progress: its odometry against its commands, control tick by control tick.

    `check` is called at each tick with the command about to be sent;
    `thawed` first, to learn whether the action was frozen since the last
    tick (then the watch starts afresh: the wheels were parked, or lent).
    """

    __slots__ = (
        "_base",
        "_command",
        "_commanded",
        "_drive",
        "_frozen",
        "_handle",
        "_name",
        "_stalled",
        "_start",
        "_turned",
        "_yaw",
    )
    _start: tuple[float, float]  # where the odometry was at the last progress
    _stalled: float  # seconds of ticks since then
    _commanded: tuple[float, float]  # metres and radians commanded since then
    _turned: float  # radians turned since then
    _yaw: float  # at the last tick

    def __init__(self, base: DriveBase, handle: ActionHandle[Any] | None, name: str) -> None:
        self._base, self._handle, self._name = base, handle, name
        self._drive = base.backend  # (read at every tick: the backend's own, one call less)
        self._frozen = self._frozen_time()
        self._command: Velocity = (0.0, 0.0)  # what the wheels were told at the last tick
        self._restart(*base.odom_pose())

    def thawed(self) -> bool:
        """Whether the action was frozen since the last tick (the watch then starts afresh)."""
        handle = self._handle  # (`_frozen_time`, inlined: at every tick)
        frozen = 0.0 if handle is None else handle.frozen_time()
        if frozen == self._frozen:
            return False
        self._frozen, self._command = frozen, (0.0, 0.0)
        return True

    def check(self, command: Velocity) -> None:
        """Note this tick, before ``command`` is sent.

        Raises:
            StallError: The wheels were commanded to move for the base's
                ``stall_timeout`` seconds, and the odometry showed no progress.
        """
        drive = self._drive
        x, y, yaw = drive.odom_pose()
        v, w = self._command
        period = drive.control_period
        self._commanded = (
            self._commanded[0] + abs(v) * period,
            self._commanded[1] + abs(w) * period,
        )
        self._turned += wrap_angle(yaw - self._yaw)
        self._yaw, self._command = yaw, command
        if not (v or w) or self._progressed(math.hypot(x - self._start[0], y - self._start[1])):
            self._restart(x, y, yaw)
            return
        self._stalled += period
        if self._stalled + _SLACK >= self._base.stall_timeout:
            raise StallError(self._name, (v, w), self._stalled, self._base.stall_timeout)

    def _progressed(self, moved: float) -> bool:
        travel, turn = self._commanded
        return (travel > 0 and moved >= min(STALL_TRAVEL, _SHARE * travel)) or (
            turn > 0 and abs(self._turned) >= min(STALL_TURN, _SHARE * turn)
        )

    def _restart(self, x: float, y: float, yaw: float) -> None:
        """Look for progress from here, the odometry's pose ``(x, y, yaw)``."""
        self._yaw = yaw
        self._start, self._stalled, self._commanded, self._turned = (x, y), 0.0, (0.0, 0.0), 0.0

    def _frozen_time(self) -> float:
        return 0.0 if self._handle is None else self._handle.frozen_time()
