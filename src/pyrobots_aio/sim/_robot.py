"""SimRobot: the simulated differential-drive robot, with its motion actions.

Every motion action locks `WHEELS`, drives through a per-tick controller on
the robot's own odometry (as a robot's firmware would), and stops the wheels
when it ends for any reason — cancellation and preemption included.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from .._exceptions import SimulationError
from ..actions import action, lock
from ..resources import Resource
from ..robot import Robot
from ._backend import SimBackend
from ._frames import WorldFrames
from ._odometry import wrap_angle
from ._world import SimWorld

if TYPE_CHECKING:
    from pathlib import Path

    from ..poses import PoseLike

WHEELS = Resource("wheels")
"""The drive wheels: every motion action holds them."""

DISTANCE_TOLERANCE = 0.002
"""Metres: `SimRobot.drive_distance` and `SimRobot.navigate_to` stop at most this far off.

They stop at the control tick nearest the goal, by their own measure (odometry
for the first, the map pose for the second): closer, at their slowest speeds.
"""
ANGLE_TOLERANCE = 0.005
"""Radians: `SimRobot.rotate_angle` and `SimRobot.navigate_to` stop at most this far off.

As `DISTANCE_TOLERANCE`; odometry (`rotate_angle`) also slips from the true
heading by about 0.05% of the turn.
"""
DOCK_APPROACH = (0.45, 0.0, 0.0, "dock")
"""Where `SimRobot.dock` goes before reversing onto the dock (in the dock's frame)."""
_MIN_V, _MIN_W, _GAIN = 0.03, 0.15, 3.0
_DOCK_SPEED, _DOCK_REVERSE_LIMIT = 0.05, 0.7


def _checked(name: str, value: float, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        msg = f"{name} must be a finite number, got {value!r}"
        raise ValueError(msg)
    if positive and value <= 0:
        msg = f"{name} must be positive, got {value!r}"
        raise ValueError(msg)
    return float(value)


def _ramp(remaining: float, top: float, floor: float) -> float:
    """Speed toward a goal ``remaining`` away: full speed, slowing down near it."""
    return math.copysign(min(top, max(floor, _GAIN * abs(remaining))), remaining)


class SimRobot(Robot):
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

    Args:
        seed: Seeds the sensor noise: the same seed and commands give the same run.
        realtime: False (default) runs in lockstep virtual time, as fast as the
            CPU allows (start it with `pyrobots_aio.sim.run` or the
            ``virtual_time`` pytest marker); True follows the wall clock.
        model: Another MJCF scene containing the robot (default: the shipped arena).
        control_rate: Control ticks per second; sensors reach ``robot.state`` each tick.
        physics_dt: The physics step, in seconds.
        **options: `Robot` options (``max_actions``, ``cancel_grace``, ``instruments`` ...).

    Example:
        >>> from pyrobots_aio.sim import SimRobot, run
        >>> async def main() -> bool:
        ...     async with SimRobot() as robot:
        ...         await robot.undock()
        ...         await robot.drive_distance(0.5)
        ...         return robot.state.docked
        >>> run(main)
        False
    """

    def __init__(
        self,
        *,
        seed: int = 0,
        realtime: bool = False,
        model: str | Path | None = None,
        control_rate: float = 50.0,
        physics_dt: float = 0.002,
        **options: Any,
    ) -> None:
        self.world = SimWorld(model, seed=seed, physics_dt=physics_dt)
        self.sim = SimBackend(self.world, control_rate=control_rate, realtime=realtime)
        super().__init__(backend=self.sim, **options)
        self.seed = seed
        self.realtime = realtime
        self.poses.add_frame_provider(WorldFrames(self.world))

    # -- direct commands --------------------------------------------------

    def drive(self, v: float, w: float) -> None:
        """Command linear speed ``v`` (m/s) and angular speed ``w`` (rad/s) until changed.

        A plain call that does not lock the wheels; actions lock `WHEELS` first.
        """
        self.world.set_command(_checked("v", v), _checked("w", w))

    def stop(self) -> None:
        """Stop the wheels."""
        self.world.stop()

    # -- motion actions ---------------------------------------------------

    @action
    @lock(WHEELS)
    async def drive_distance(self, distance: float, speed: float = 0.2) -> float:
        """Drive straight ``distance`` metres (negative: backwards); return the distance done."""
        goal = _checked("distance", distance)
        top = _checked("speed", speed, positive=True)
        x0, y0, _ = self.world.odom_pose()

        def travelled() -> float:
            x, y, _ = self.world.odom_pose()
            return math.hypot(x - x0, y - y0)

        def step() -> bool:
            remaining = abs(goal) - travelled()
            v = _ramp(remaining, top, _MIN_V)
            if self._arrived(remaining, v, DISTANCE_TOLERANCE):
                self.world.stop()
                return True
            self.world.set_command(v if goal >= 0 else -v, 0.0)
            return False

        await self._steer(step)
        return math.copysign(travelled(), goal)

    @action
    @lock(WHEELS)
    async def rotate_angle(self, angle: float, speed: float = 1.0) -> float:
        """Turn in place by ``angle`` radians (positive: counter-clockwise); return the turn."""
        goal = _checked("angle", angle)
        top = _checked("speed", speed, positive=True)
        turned, last = 0.0, self.world.odom_pose()[2]

        def step() -> bool:
            nonlocal turned, last
            yaw = self.world.odom_pose()[2]
            turned, last = turned + wrap_angle(yaw - last), yaw
            remaining = goal - turned
            w = _ramp(remaining, top, _MIN_W)
            if self._arrived(remaining, w, ANGLE_TOLERANCE):
                self.world.stop()
                return True
            self.world.set_command(0.0, w)
            return False

        await self._steer(step)
        return turned

    @action
    @lock(WHEELS)
    async def navigate_to(self, pose: PoseLike, speed: float = 0.2) -> None:
        """Go to ``pose`` (any format ``robot.poses.get`` reads): turn, drive, then turn to its yaw.

        It localises on the map, as a robot with a localisation stack (or the
        Create 3 with its dock beacon) would, and follows a straight line: no
        planning, obstacles are the bumper's business.
        """
        top = _checked("speed", speed, positive=True)
        target = self.poses.inframe(pose, "map")
        tx, ty, tyaw = target.x, target.y, self.poses.euler(target)[2]

        def step() -> bool:
            x, y, yaw = self.world.base_pose()
            dist = math.hypot(tx - x, ty - y)
            if dist > DISTANCE_TOLERANCE * 5:
                error = wrap_angle(math.atan2(ty - y, tx - x) - yaw)
                v = 0.0 if abs(error) > 0.3 else _ramp(dist, top, _MIN_V)
                self.world.set_command(v, _ramp(error, 1.0, _MIN_W) if abs(error) > 0.01 else 0.0)
                return False
            error = wrap_angle(tyaw - yaw)
            w = _ramp(error, 1.0, _MIN_W)
            if self._arrived(error, w, ANGLE_TOLERANCE):
                self.world.stop()
                return True
            self.world.set_command(0.0, w)
            return False

        await self._steer(step)

    @action
    @lock(WHEELS)
    async def undock(self) -> None:
        """Leave the dock: drive 0.35 m straight ahead (nothing to do if not docked)."""
        if self.state["docked"]:
            await self.drive_distance(0.35)

    @action
    @lock(WHEELS)
    async def dock(self) -> None:
        """Go in front of the dock, then reverse slowly onto it until ``docked``.

        Raises:
            SimulationError: The robot reversed 0.7 m without docking.
        """
        if self.state["docked"]:
            return
        await self.navigate_to(DOCK_APPROACH)
        x0, y0, _ = self.world.odom_pose()

        def step() -> bool:
            if self.state["docked"]:
                self.world.stop()
                return True
            x, y, _ = self.world.odom_pose()
            if math.hypot(x - x0, y - y0) > _DOCK_REVERSE_LIMIT:
                msg = f"docking failed: reversed {_DOCK_REVERSE_LIMIT} m without touching the dock"
                raise SimulationError(msg)
            self.world.set_command(-_DOCK_SPEED, 0.0)
            return False

        await self._steer(step)

    def _arrived(self, remaining: float, speed: float, tolerance: float) -> bool:
        """Whether to stop now, ``remaining`` from the goal and about to go at ``speed``.

        It stops at the control tick nearest the goal: within ``tolerance`` and
        within half the way one more tick at ``speed`` would go. (Stopping at the
        first tick within tolerance stopped short by up to the tolerance, every time.)
        """
        return abs(remaining) <= min(tolerance, abs(speed) * self.sim.period / 2)

    async def _steer(self, step: Any) -> None:
        """Run ``step`` now and after every tick until it returns True; stop the wheels after."""
        try:
            if not step():
                await self.sim.control(step)
        finally:
            self.world.stop()
