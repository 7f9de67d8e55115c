"""Docking through the base's own action servers, for a profile that has them (the Create 3's).

A Create 3 docks and undocks itself: it sees its dock's beacon, which the
executive does not. So `Ros2Robot.dock` and ``undock`` send the goal to the
base's ``dock`` and ``undock`` action servers when its profile names them
(``CREATE3_ACTIONS``), and drive there themselves (`DriveBase.dock`)
otherwise. The goal is a child action: cancelling the docking (a bumper
reflex, a preemption) cancels the goal on the base, which stops.

Freezing it (a pause, or a suspension: ``random_walk(robot, on_bump="suspend")``'s
reflex borrowing the wheels) cancels the base's goal too, at once: a base left
to carry on with its own goal would fight the reflex for the wheels. The base
stops, and once the docking thaws it sends the goal again, from wherever the
robot then is (the base's dock action starts from anywhere in sight of its dock).
"""

from __future__ import annotations

from typing import Any

from .._exceptions import ActionInterrupted, MotionError
from ..actions import ActionHandle, action, lock
from ..lowlevel import park
from ..motion import WHEELS, DriveBase
from ._create3 import CREATE3, CREATE3_ACTIONS, create3_action

__all__ = ["ProfileDocking"]

_SERVERS = {CREATE3.name: CREATE3_ACTIONS}
"""The action servers of each profile that has some, by name."""

FROZEN = "the docking froze (paused, or suspended): the base stops, and gets the goal again on thaw"
"""The reason the base's goal is cancelled with when the docking or undocking freezes."""


def _freeze(robot: ProfileDocking) -> None:
    """The pause hook: stop the wheels, and cancel the base's goal, which is sent again on thaw."""
    park(robot)
    goal = robot._base_goal
    if goal is not None:
        goal.cancel(FROZEN)


class ProfileDocking(DriveBase):
    """A `DriveBase` that docks and undocks through its profile's action servers, if any."""

    _base_goal: ActionHandle[Any] | None = None
    """The goal `_base_action` awaits (set by it alone; `_freeze` cancels it)."""

    def _served(self, name: str) -> bool:
        profile = getattr(self.backend, "profile", None)  # a Ros2Backend's
        return name in _SERVERS.get(getattr(profile, "name", ""), {})

    async def _base_action(self, name: str) -> Any:
        """The result of the base's action ``name``, sent again each time a freeze cancels it."""
        while True:
            self._base_goal = goal = self.ros2.goal(name, create3_action(name).Goal())
            try:
                return await goal
            except ActionInterrupted as interrupted:
                if interrupted.reason != FROZEN:
                    raise
            finally:
                self._base_goal = None

    # Not `super().dock()` when there is no server: that would start a second ``dock``
    # action inside this one. `DriveBase`'s body (its lock included) runs in this action.

    @action(on_pause=_freeze)
    async def undock(self) -> None:
        """Leave the dock: the base's ``undock`` action (a Create 3's), or `DriveBase.undock`."""
        if not self._served("undock"):
            return await DriveBase.undock.fn(self)
        async with lock(WHEELS):
            await self._base_action("undock")
        return None

    @action(on_pause=_freeze)
    async def dock(self) -> None:
        """Dock: the base's ``dock`` action (a Create 3's), or `DriveBase.dock`.

        Raises:
            MotionError: The base's dock action ended without docking.
        """
        if not self._served("dock"):
            return await DriveBase.dock.fn(self)
        async with lock(WHEELS):
            result = await self._base_action("dock")
            if not result.is_docked:
                msg = f"docking failed: the base's dock action ended undocked ({result!r})"
                raise MotionError(msg)
            await self.wait(lambda robot: bool(robot.state["docked"]))  # dock_status says so
        return None
