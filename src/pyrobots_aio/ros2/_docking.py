"""Docking through the base's own action servers, for a profile that has them (the Create 3's).

A Create 3 docks and undocks itself: it sees its dock's beacon, which the
executive does not. So `Ros2Robot.dock` and ``undock`` send the goal to the
base's ``dock`` and ``undock`` action servers when its profile names them
(``CREATE3_ACTIONS``), and drive there themselves (`DriveBase.dock`)
otherwise. The goal is a child action: cancelling the docking (a bumper
reflex, a preemption) cancels the goal on the base, which stops.
"""

from __future__ import annotations

from .._exceptions import MotionError
from ..actions import action, lock
from ..lowlevel import park
from ..motion import WHEELS, DriveBase
from ._create3 import CREATE3, CREATE3_ACTIONS, create3_action

__all__ = ["ProfileDocking"]

_SERVERS = {CREATE3.name: CREATE3_ACTIONS}
"""The action servers of each profile that has some, by name."""


def _park(robot: ProfileDocking) -> None:
    """`pyrobots_aio.motion`'s pause hook, typed for this class (as `action` checks it)."""
    park(robot)


class ProfileDocking(DriveBase):
    """A `DriveBase` that docks and undocks through its profile's action servers, if any."""

    def _served(self, name: str) -> bool:
        profile = getattr(self.backend, "profile", None)  # a Ros2Backend's
        return name in _SERVERS.get(getattr(profile, "name", ""), {})

    # Not `super().dock()` when there is no server: that would start a second ``dock``
    # action inside this one. `DriveBase`'s body (its lock included) runs in this action.

    @action
    async def undock(self) -> None:
        """Leave the dock: the base's ``undock`` action (a Create 3's), or `DriveBase.undock`."""
        if not self._served("undock"):
            return await DriveBase.undock.fn(self)
        async with lock(WHEELS):
            await self.ros2.goal("undock", create3_action("undock").Goal())
        return None

    @action(on_pause=_park)
    async def dock(self) -> None:
        """Dock: the base's ``dock`` action (a Create 3's), or `DriveBase.dock`.

        Raises:
            MotionError: The base's dock action ended without docking.
        """
        if not self._served("dock"):
            return await DriveBase.dock.fn(self)
        async with lock(WHEELS):
            result = await self.ros2.goal("dock", create3_action("dock").Goal())
            if not result.is_docked:
                msg = f"docking failed: the base's dock action ended undocked ({result!r})"
                raise MotionError(msg)
            await self.wait(lambda robot: bool(robot.state["docked"]))  # dock_status says so
        return None
