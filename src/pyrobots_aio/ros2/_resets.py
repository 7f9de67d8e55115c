"""Odometry resets: a driver that restarts is noticed, and the robot's pose goes on unbroken.

A base's driver that restarts starts its odometry again from zero (and,
on simulated time, its stamps too). Read as it comes, that is a jump of
the robot's pose: a ``drive_distance`` measuring from its start would think
it arrived, or had to go back. `OdometryResets` notices the jump (a stamp
going back, or a pose that moved farther between two messages than its
reported speeds explain, by `JUMP`), logs it as a reset, and from then on places the new readings
after the last pose, as if the driver had not restarted (the robot does not
move while its driver restarts). The motion layer sees a continuous pose.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..motion import Pose2D
    from ._profiles import Odometry

_log = logging.getLogger("pyrobots_aio.ros2")

JUMP = (0.25, 0.5)
"""Metres and radians beyond what the reported speeds explain that make a jump a reset.

Between two messages a base moves its speed (the larger of the two
messages' ``v``, ``w``) times the time between them, counted up to
``horizon``: longer without odometry, the base is stale and told to stop.
A base at 0.5 m/s and 2 rad/s moves 0.01 m and 0.04 rad between two
messages at 50 Hz; these margins are some twenty messages' worth.
"""


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """Pose ``b`` (given in the frame that is at ``a``) expressed where ``a`` is given."""
    ax, ay, ayaw = a
    bx, by, byaw = b
    c, s = math.cos(ayaw), math.sin(ayaw)
    return ax + c * bx - s * by, ay + s * bx + c * by, math.remainder(ayaw + byaw, math.tau)


def inverse(a: Pose2D) -> Pose2D:
    """The pose ``b`` with ``compose(a, b) == (0, 0, 0)``."""
    x, y, yaw = a
    c, s = math.cos(yaw), math.sin(yaw)
    return -c * x - s * y, s * x - c * y, -yaw


def _shown(pose: Pose2D) -> str:
    return "({:.3f}, {:.3f}, {:.3f})".format(*pose)


class OdometryResets:
    """Odometry readings made continuous across resets of the driver.

    Args:
        topic: The odometry topic's name, for the log (its full name once subscribed).
        horizon: Seconds of motion at the reported speeds a gap between two
            messages can explain at most (the base is stopped when odometry is stale).
    """

    def __init__(self, topic: str, horizon: float) -> None:
        self.topic, self.horizon = topic, horizon
        self.count = 0
        """Resets noticed since the last `clear`."""
        self._last: Odometry | None = None
        self._received = 0.0
        self._rebase: Pose2D = (0.0, 0.0, 0.0)

    def pose(self, reading: Odometry, current: Pose2D, now: float) -> Pose2D:
        """The pose ``reading`` gives in the robot's ``odom`` frame.

        Args:
            reading: The odometry message, decoded.
            current: The robot's last pose (what a reset goes on from).
            now: The robot's time (for messages without stamps).
        """
        last, self._last = self._last, reading
        received, self._received = self._received, now
        stamped = last is not None and last.stamp > 0.0 and reading.stamp > 0.0
        gap = reading.stamp - last.stamp if stamped and last is not None else now - received
        if last is not None and _is_reset(last, reading, min(abs(gap), self.horizon)):
            self._rebase = compose(current, inverse(reading.pose))
            self.count += 1
            _log.warning(
                "odometry on %s was reset (a driver restart?): it jumped from %s to %s, its "
                "stamp from %.3f to %.3f s; the robot's pose goes on from %s, and motions do "
                "not act on the jump",
                self.topic,
                _shown(last.pose),
                _shown(reading.pose),
                last.stamp,
                reading.stamp,
                _shown(current),
            )
        return compose(self._rebase, reading.pose)

    def clear(self) -> None:
        """Forget the last reading and the rebase (the robot stopped)."""
        self._last, self._received = None, 0.0
        self._rebase, self.count = (0.0, 0.0, 0.0), 0


def _is_reset(last: Odometry, reading: Odometry, gap: float) -> bool:
    """Whether ``reading`` jumped from ``last`` farther than ``gap`` seconds of motion explain."""
    (x0, y0, yaw0), (x1, y1, yaw1) = last.pose, reading.pose
    metres, radians = JUMP
    went_back = 0.0 < reading.stamp < last.stamp
    moved = math.hypot(x1 - x0, y1 - y0) - max(abs(last.v), abs(reading.v)) * gap
    turned = abs(math.remainder(yaw1 - yaw0, math.tau)) - max(abs(last.w), abs(reading.w)) * gap
    return went_back or moved > metres or turned > radians
