"""SimRobot: the simulated differential-drive robot, a `DriveBase` over MuJoCo.

Its backend is a `SimBackend` ticking a `SimWorld`; the motion actions come
from `DriveBase`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..motion import DriveBase
from ._backend import SimBackend
from ._world import SimWorld

if TYPE_CHECKING:
    from pathlib import Path


__all__ = ["SimRobot"]

_DEFAULT_DT = 0.002


class SimRobot(DriveBase):
    """The MuJoCo simulation of a Create-3-sized robot in its arena; it starts docked.

    Time: the event loop's clock is the simulation's. When the robot starts
    (``async with robot``), the world's clock is set to the loop's time, so
    ``robot.time()``, ``robot.world.time`` and the timestamps in
    ``robot.state`` agree exactly at every control tick, however long the loop
    ran before (a robot entered at loop time 5 s starts its simulation at 5 s).
    Between runs the physics is paused: entered again later, the robot goes
    on from where it stood, at the loop's new time (``robot.world.steps``
    counts only the simulated steps). In real time the world's clock reads
    each tick's scheduled time; the loop's runs on between ticks.

    Motion: ``drive``, ``stop`` and the motion actions are `DriveBase`'s;
    odometry is the world's dead reckoning from the wheel encoders, and the
    map pose (for ``navigate_to``) is the true pose, as a localised robot's.

    Args:
        seed: Seeds the sensor noise: the same seed and commands give the same run.
        realtime: False (default) runs in lockstep virtual time, as fast as the
            CPU allows (start it with `pyrobots_aio.sim.run` or the
            ``virtual_time`` pytest marker); True follows the wall clock.
        model: Another MJCF scene containing the robot (default: the shipped arena).
        world: A robot of a world built beforehand, to share it with other
            simulated robots: ``SimWorld(robots=2).robots[1]`` (then the world
            gives the model, the seed and ``physics_dt``; pass none of them).
        control_rate: Control ticks per second; sensors reach ``robot.state`` each tick.
        physics_dt: The physics step, in seconds.
        **options: `DriveBase` and `Robot` options (``stall_timeout``, ``max_actions``,
            ``instruments`` ...).

    Examples:
        >>> from pyrobots_aio.sim import SimRobot, run
        >>> async def main() -> bool:
        ...     async with SimRobot() as robot:
        ...         await robot.undock()
        ...         await robot.drive_distance(0.5)
        ...         return robot.state.docked
        >>> run(main)
        False

        Two robots in one world (each on its own dock, 0.5 m apart), one program:

        >>> import asyncio
        >>> from pyrobots_aio.sim import SimWorld
        >>> async def pair() -> tuple[bool, bool, float]:
        ...     first, second = (SimRobot(world=w) for w in SimWorld(robots=2).robots)
        ...     async with first, second:
        ...         await asyncio.gather(first.undock(), second.undock())
        ...         apart = second.map_pose()[1] - first.map_pose()[1]
        ...         return first.state.docked, second.state.docked, round(apart, 2)
        >>> run(pair)
        (False, False, 0.5)
    """

    def __init__(
        self,
        *,
        seed: int = 0,
        realtime: bool = False,
        model: str | Path | None = None,
        world: SimWorld | None = None,
        control_rate: float = 50.0,
        physics_dt: float = _DEFAULT_DT,
        **options: Any,
    ) -> None:
        if world is None:
            world = SimWorld(model, seed=seed, physics_dt=physics_dt)
        elif model is not None or seed != 0 or physics_dt != _DEFAULT_DT:
            msg = (
                "SimRobot(world=...) takes its model, seed and physics_dt from the world; "
                "pass them to SimWorld(...) instead"
            )
            raise ValueError(msg)
        sim = SimBackend(world, control_rate=control_rate, realtime=realtime)
        super().__init__(backend=sim, **options)
        self.sim = sim
        self.world = world
        self.seed = world.seed
        self.realtime = realtime
