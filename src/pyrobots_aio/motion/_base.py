"""DriveBase: the seam between the motion layer and any differential-drive base.

The motion actions (`DriveBase.drive_distance`, `rotate_angle`,
`navigate_to`, `dock`, `undock`) are written once here, against the
`DriveBackend` a base holds: the simulator's (`pyrobots_aio.sim.SimRobot`),
ROS 2's (``Ros2Robot``), or the in-memory one of
`pyrobots_aio.testing.FakeBase`. Every motion
action locks `WHEELS`, drives through a per-tick controller on the base's
own measures (as a robot's firmware would), and stops the wheels when it ends
for any reason, cancellation and preemption included. While the robot's
emergency stop is latched (``robot.emergency_stop(reason)``, which stops the
wheels at once), the motion actions and ``drive`` refuse to move. A motion
action that commands motion and sees no odometry progress for
`DriveBase.stall_timeout` seconds (`STALL_TIMEOUT`) fails with a `StallError`
(`StallWatch`): the robot is blocked.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from .._core._numbers import finite, shown
from .._exceptions import MotionError
from ..actions import action, current_action, lock
from ..resources import Resource
from ..robot import Robot
from ._math import MAX_DISTANCE, MAX_TURN, checked, ramp, wrap_angle
from ._stall import STALL_TIMEOUT, StallWatch

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..poses import Pose2D, PoseLike
    from ._backend import DriveBackend
    from ._sensors import Sensor
    from ._stall import Velocity

    Step = Callable[[], Velocity | None]  # the command for the next tick; None: arrived

WHEELS = Resource("wheels")
"""The drive wheels: every motion action holds them."""

DISTANCE_TOLERANCE = 0.002
"""Metres: `DriveBase.drive_distance` and `DriveBase.navigate_to` stop at most this far off.

They stop at the control tick nearest the goal, by their own measure (odometry
for the first, the map pose for the second): closer, at their slowest speeds.
"""
ANGLE_TOLERANCE = 0.005
"""Radians: `DriveBase.rotate_angle` and `DriveBase.navigate_to` stop at most this far off.

As `DISTANCE_TOLERANCE`; odometry (`rotate_angle`) also slips from the true
heading (on the simulator, by about 0.05% of the turn).
"""
DOCK_APPROACH = (0.45, 0.0, 0.0, "dock")
"""Where `DriveBase.dock` goes before reversing onto the dock (in the dock's frame)."""
UNDOCK_DISTANCE = 0.35
"""Metres `DriveBase.undock` drives straight ahead, off the dock."""
_SEAM = (  # DriveBackend's members: named in the error when missing (isinstance only says no)
    "start",
    "stop",
    "sensors",
    "frames",
    "control_period",
    "set_velocity",
    "odom_pose",
    "map_pose",
    "control",
)
_MIN_V, _MIN_W = 0.03, 0.15
_DOCK_SPEED, _DOCK_REVERSE_LIMIT = 0.05, 0.7
_METRES = "drive_distance takes metres, at most 100 km either way"
_RADIANS = "rotate_angle turns by radians, at most 1000 turns either way (math.radians(degrees))"


def park(robot: DriveBase) -> None:
    """The motion actions' pause hook: stop the wheels (the controller resumes on thaw)."""
    robot.stop()


class DriveBase(Robot):
    """A differential-drive robot base: ``drive(v, w)``, ``stop()`` and the motion actions.

    The seam. A base is a `DriveBackend` (velocity command, odometry, map
    pose, control ticks, frames, sensors), which the robot holds and starts
    with itself; the motion actions are written once here against it. It
    publishes the state keys of its `sensors` (the standard robot's:
    ``bumper``, ``bumper_left``, ``bumper_right``, ``ir_<position>``,
    ``cliff_<position>``, ``docked``), ``v`` and ``w``, and provides the
    frames ``odom``, ``base_link`` and, for `dock`, ``dock``.

    Args:
        backend: The base's `DriveBackend`.
        stall_timeout: Seconds a motion action may command motion without
            odometry progress before it fails with a `StallError` (default
            `STALL_TIMEOUT`, 1.5 s; `stall_timeout` changes it later).
        **options: `Robot` options (``instruments``, ``max_actions`` ...).

    Examples:
        >>> from pyrobots_aio.sim import run
        >>> from pyrobots_aio.testing import FakeBase
        >>> async def main() -> float:
        ...     async with FakeBase() as robot:
        ...         await robot.undock()
        ...         return round(await robot.rotate_angle(1.0), 2)
        >>> run(main)
        1.0
    """

    def __init__(
        self, *, backend: DriveBackend, stall_timeout: float = STALL_TIMEOUT, **options: Any
    ) -> None:
        missing = [name for name in _SEAM if not hasattr(backend, name)]
        if missing:
            msg = (
                f"a DriveBase needs a DriveBackend; {backend!r} lacks {', '.join(missing)} "
                "(see pyrobots_aio.motion.DriveBackend)"
            )
            raise TypeError(msg)
        super().__init__(backend=backend, **options)
        self._drive = backend
        self.stall_timeout = stall_timeout
        self.poses.add_frame_provider(backend.frames)

    @property
    def backend(self) -> DriveBackend:
        """The base's `DriveBackend`, started and stopped with the robot."""
        return self._drive

    @property
    def stall_timeout(self) -> float:
        """Seconds a motion action may command motion without odometry progress.

        Past it, the action stops the wheels and fails with a `StallError` (a
        `MotionError`) naming itself, the command and the time (see `StallWatch` for what
        counts as progress). A positive number of seconds; a base whose motions
        start slowly (a heavy payload) may want more.
        """
        return self._stall_timeout

    @stall_timeout.setter
    def stall_timeout(self, seconds: float) -> None:
        self._stall_timeout = finite(
            "stall_timeout", seconds, positive=True, must="a positive number of seconds"
        )

    # -- the seam: the backend's ------------------------------------------

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The sensors the base publishes into ``robot.state`` (besides ``v`` and ``w``)."""
        return self._drive.sensors

    @property
    def control_period(self) -> float:
        """Seconds between sensor updates (control ticks)."""
        return self._drive.control_period

    def odom_pose(self) -> Pose2D:
        """The pose ``(x, y, yaw)`` dead-reckoned from the wheels, in the ``odom`` frame."""
        return self._drive.odom_pose()

    def map_pose(self) -> Pose2D:
        """The robot's pose ``(x, y, yaw)`` in the ``map`` frame (where it is localised)."""
        return self._drive.map_pose()

    async def control(self, step: Callable[[], bool]) -> None:
        """Call ``step()`` after each fresh sensor update until it returns True.

        ``step`` reads the fresh state and sets the wheel command; the motion
        actions are built on it. Cancelling the wait removes it.
        """
        await self._drive.control(step)

    # -- direct commands --------------------------------------------------

    def drive(self, v: float, w: float) -> None:
        """Command linear speed ``v`` (m/s) and angular speed ``w`` (rad/s) until changed.

        A plain call that does not lock the wheels; actions lock `WHEELS` first.
        Any finite numbers are taken; a command beyond the base's top wheel
        speed is scaled down as a whole, keeping its curvature, as a robot's
        firmware does (a simulated base's ``robot.world.command`` shows what the wheels get).

        Raises:
            ValueError: ``v`` or ``w`` is not a finite number.
            EmergencyStopError: The emergency stop is latched (``drive(0, 0)``
                is still allowed: it stops).
        """
        v, w = checked("v", v), checked("w", w)
        if v or w:
            self._refuse_motion(f"drive({v!r}, {w!r})")
        self._drive.set_velocity(v, w)

    def stop(self) -> None:
        """Stop the wheels."""
        self._drive.set_velocity(0.0, 0.0)

    def halt_actuators(self) -> None:
        """Stop the wheels (the emergency stop calls it first)."""
        self.stop()
        super().halt_actuators()

    # -- motion actions ---------------------------------------------------

    @action(on_pause=park)
    @lock(WHEELS)
    async def drive_distance(self, distance: float, speed: float = 0.2) -> float:
        """Drive straight ``distance`` metres (negative: backwards); return the distance done.

        ``distance`` is at most `MAX_DISTANCE` (100 km) either way; a larger
        one, or a number that is not finite, raises `ValueError`.
        """
        goal = checked("distance", distance, bound=MAX_DISTANCE, fix=_METRES)
        top = checked("speed", speed, positive=True)
        odom = self._drive.odom_pose  # (read at every tick: the backend's, one call less)
        x0, y0, _ = odom()

        def travelled() -> float:
            x, y, _ = odom()
            return math.hypot(x - x0, y - y0)

        def step() -> Velocity | None:
            remaining = abs(goal) - travelled()
            v = ramp(remaining, top, _MIN_V)
            if self._arrived(remaining, v, DISTANCE_TOLERANCE):
                return None
            return (v if goal >= 0 else -v, 0.0)

        await self._steer(step)
        return math.copysign(travelled(), goal)

    @action(on_pause=park)
    @lock(WHEELS)
    async def rotate_angle(self, angle: float, speed: float = 1.0) -> float:
        """Turn in place by ``angle`` radians (positive: counter-clockwise); return the turn.

        The turn is not wrapped: ``4 * math.pi`` turns twice. It is at most
        `MAX_TURN` (1000 turns) either way; more raises `ValueError`.
        """
        goal = checked("angle", angle, bound=MAX_TURN, fix=_RADIANS)
        top = checked("speed", speed, positive=True)
        odom = self._drive.odom_pose  # (read at every tick: the backend's, one call less)
        turned, last = 0.0, odom()[2]

        def step() -> Velocity | None:
            nonlocal turned, last
            yaw = odom()[2]
            turned, last = turned + wrap_angle(yaw - last), yaw
            remaining = goal - turned
            w = ramp(remaining, top, _MIN_W)
            if self._arrived(remaining, w, ANGLE_TOLERANCE):
                return None
            return (0.0, w)

        await self._steer(step)
        return turned

    @action(on_pause=park)
    @lock(WHEELS)
    async def navigate_to(self, pose: PoseLike, speed: float = 0.2) -> None:
        """Go to ``pose`` (any format ``robot.poses.get`` reads): turn, drive, then turn to its yaw.

        It localises on the map (`map_pose`), as a robot with a localisation
        stack (or the Create 3 with its dock beacon) would, and follows a
        straight line: no planning, obstacles are the bumper's business.
        """
        top = checked("speed", speed, positive=True)
        target = self.poses.inframe(pose, "map")
        tx, ty, tyaw = target.x, target.y, self.poses.euler(target)[2]
        x0, y0, _ = self.map_pose()
        if (far := math.hypot(tx - x0, ty - y0)) > MAX_DISTANCE:
            msg = (
                f"navigate_to({shown(pose)}): the goal is {far:g} m away, beyond {MAX_DISTANCE:g} m"
            )
            raise ValueError(msg)

        def step() -> Velocity | None:
            x, y, yaw = self.map_pose()
            dist = math.hypot(tx - x, ty - y)
            if dist > DISTANCE_TOLERANCE * 5:
                error = wrap_angle(math.atan2(ty - y, tx - x) - yaw)
                v = 0.0 if abs(error) > 0.3 else ramp(dist, top, _MIN_V)
                return (v, ramp(error, 1.0, _MIN_W) if abs(error) > 0.01 else 0.0)
            error = wrap_angle(tyaw - yaw)
            w = ramp(error, 1.0, _MIN_W)
            if self._arrived(error, w, ANGLE_TOLERANCE):
                return None
            return (0.0, w)

        await self._steer(step)

    @action
    @lock(WHEELS)
    async def undock(self) -> None:
        """Leave the dock: drive `UNDOCK_DISTANCE` straight ahead (nothing to do if not docked)."""
        if self.state["docked"]:
            await self.drive_distance(UNDOCK_DISTANCE)

    @action(on_pause=park)
    @lock(WHEELS)
    async def dock(self) -> None:
        """Go in front of the dock (`DOCK_APPROACH`), then reverse slowly onto it until ``docked``.

        Reversing is blind: it keeps the line the approach left it on. So if
        the action is frozen while reversing (paused, or suspended while a
        reflex borrows the wheels and moves the robot), it lines up in front
        of the dock again before reversing again.

        Raises:
            MotionError: The robot reversed 0.7 m without docking, or stalled
                (`StallError`).
        """
        while not self.state["docked"]:
            await self.navigate_to(DOCK_APPROACH)
            await self._reverse_onto_dock()

    async def _reverse_onto_dock(self) -> None:
        """Reverse slowly until ``docked``; return early if frozen meanwhile (the line is lost)."""
        x0, y0, _ = self.odom_pose()

        def step() -> Velocity | None:
            if self.state["docked"]:
                return None
            x, y, _ = self.odom_pose()
            if math.hypot(x - x0, y - y0) > _DOCK_REVERSE_LIMIT:
                msg = f"docking failed: reversed {_DOCK_REVERSE_LIMIT} m without touching the dock"
                raise MotionError(msg)
            return (-_DOCK_SPEED, 0.0)

        await self._steer(step, until_thawed=True)

    def _arrived(self, remaining: float, speed: float, tolerance: float) -> bool:
        """Whether to stop now, ``remaining`` from the goal and about to go at ``speed``.

        It stops at the control tick nearest the goal: within ``tolerance`` and
        within half the way one more tick at ``speed`` would go. (Stopping at the
        first tick within tolerance stopped short by up to the tolerance, every time.)
        """
        return abs(remaining) <= min(tolerance, abs(speed) * self._drive.control_period / 2)

    async def _steer(self, step: Step, *, until_thawed: bool = False) -> None:
        """Send the command ``step`` returns, now and after every tick, until it returns None.

        The wheels stop when it ends, for any reason. A command that makes no
        progress for `stall_timeout` seconds ends it with a `StallError`
        (`StallWatch`). With ``until_thawed``, it also ends at the first tick
        after the action was frozen (paused, or suspended: the robot may have
        been moved meanwhile).

        Refused (`EmergencyStopError`) while the emergency stop is latched.
        """
        handle = current_action.get()
        name = handle.name if handle is not None else "motion"
        self._refuse_motion(name)
        watch = StallWatch(self, handle, name)

        def tick() -> bool:
            if watch.thawed() and until_thawed:
                return True
            command = step()
            if command is None:
                self.stop()
                return True
            watch.check(command)
            self._drive.set_velocity(*command)
            return False

        try:
            if not tick():
                await self.control(tick)
        finally:
            self.stop()
