"""What telemetry reads of a robot: a protocol, so that telemetry sits below the robot.

The robot owns a live view (``Robot(serve=PORT)``) and so imports telemetry;
telemetry in turn reads the robot's state, poses, clock and instruments. A
protocol of those four carries that dependency without an upward import.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from .._core._instrument import Instruments
    from ..poses import PoseManager
    from ..state import StateStore


class TelemetrySource(Protocol):
    """A robot as telemetry sees it: its state, poses, clock and instruments.

    `pyrobots_aio.Robot` is one.

    Examples:
        >>> from pyrobots_aio import Robot
        >>> from pyrobots_aio.sim import run
        >>> from pyrobots_aio.telemetry import StateSampler
        >>> async def main() -> list[tuple[float, dict[str, object]]]:
        ...     seen: list[tuple[float, dict[str, object]]] = []
        ...     sampler = StateSampler(lambda time, values, pose: seen.append((time, values)))
        ...     async with Robot() as robot:
        ...         sampler.start(robot)
        ...         robot.state.speed = 0.5
        ...         await robot.sleep(1)
        ...         robot.state.speed = 0.5  # the same value again: no news
        ...         robot.state.speed = 0.7
        ...         sampler.stop()
        ...     return seen
        >>> run(main)
        [(0.0, {'speed': 0.5}), (1.0, {'speed': 0.7})]
    """

    @property
    def state(self) -> StateStore:
        """The state the samplers subscribe to."""
        ...

    @property
    def poses(self) -> PoseManager:
        """Where the pose of the robot's frame comes from."""
        ...

    @property
    def instruments(self) -> Instruments:
        """Where the live view hears the executive's events."""
        ...

    def time(self) -> float:
        """The loop's time, in seconds."""
        ...
