"""DriveBackend: what a `DriveBase` holds, the one way a differential-drive base plugs in."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..robot import Backend

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..poses import FrameProvider, Pose2D
    from ._sensors import Sensor


@runtime_checkable
class DriveBackend(Backend, Protocol):
    """A base's connection to its wheels and sensors: the simulator's, the fake's, ROS 2's.

    A `DriveBase` holds one and gets the motion actions on top. As every
    `Backend`, it starts inside ``async with robot`` (``start`` begins
    publishing the `sensors` into ``robot.state``) and stops once every
    action is done. While it runs:

    - ``set_velocity(v, w)`` commands ``v`` (m/s) and ``w`` (rad/s), finite
      numbers (`DriveBase.drive` checks them), until the next command;
    - ``odom_pose()`` is the pose dead-reckoned in the ``odom`` frame, and
      ``map_pose()`` the pose in ``map`` (where the base is localised);
    - ``await control(step)`` calls ``step()`` after each fresh sensor
      update (a control tick, an odometry message) until it returns True, an
      exception from ``step`` ending the wait with it (`Controllers` keeps
      the books); ``control_period`` is the seconds between two updates;
    - ``frames`` places ``odom``, ``base_link`` and ``dock`` for ``robot.poses``.

    Examples:
        >>> from pyrobots_aio.testing import FakeBase
        >>> isinstance(FakeBase().backend, DriveBackend)
        True
    """

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The sensors it publishes into ``robot.state`` (besides ``v`` and ``w``)."""

    @property
    def frames(self) -> FrameProvider:
        """The frames ``odom``, ``base_link`` and ``dock`` (and maybe more), for ``robot.poses``."""

    @property
    def control_period(self) -> float:
        """Seconds between sensor updates (control ticks)."""

    def set_velocity(self, v: float, w: float) -> None:
        """Command ``v`` (m/s) and ``w`` (rad/s), finite numbers, until the next command."""

    def odom_pose(self) -> Pose2D:
        """The pose ``(x, y, yaw)`` dead-reckoned from the wheels, in the ``odom`` frame."""

    def map_pose(self) -> Pose2D:
        """The pose ``(x, y, yaw)`` in the ``map`` frame (where the base is localised)."""

    async def control(self, step: Callable[[], bool]) -> None:
        """Call ``step()`` after each fresh sensor update until it returns True."""
