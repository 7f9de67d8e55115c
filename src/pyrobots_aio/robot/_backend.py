"""Backend: what connects a robot to hardware or a simulator."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

if TYPE_CHECKING:
    from ._robot import Robot


@runtime_checkable
class Backend(Protocol):
    """A robot's connection to the world, started and stopped with the robot.

    ``start`` runs inside ``async with robot`` before any user code; it may start
    background work (a control loop writing sensors into ``robot.state``) that
    ``stop`` ends. ``stop`` runs after every action is done.
    """

    async def start(self, robot: Robot) -> None:
        """Connect and start publishing to ``robot``."""

    async def stop(self) -> None:
        """Stop everything ``start`` started."""
