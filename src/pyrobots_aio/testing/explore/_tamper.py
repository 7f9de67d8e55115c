"""Tamper: a ticked base's readings, held, silenced or frozen for a while.

A held bump must stay pressed although the base publishes its bumper every
tick, a silent sensor must stop being published, stale odometry must stop
moving: each has to happen where the base reads its world. `FakeBase` and
`SimRobot` tick a world (``robot.backend.world``) whose ``read_sensors`` and
``odom_pose`` the base calls each tick; the tamper shadows those two methods
on that one world object for the run, and removes its shadows afterwards.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ... import Robot
    from ...motion import Pose2D

_SHADOWED = ("read_sensors", "odom_pose")


class Tamper:
    """What the base's world reads, changed until given times (the robot's clock)."""

    def __init__(self, robot: Robot, world: Any) -> None:
        self._robot, self._world = robot, world
        self._read_sensors = world.read_sensors
        self._odom_pose = world.odom_pose
        self._forced: dict[str, tuple[object, float]] = {}  # key: (value, until)
        self._silent: dict[str, float] = {}  # key: until
        self._odometry: tuple[Pose2D, float] | None = None  # frozen pose, until
        self._shadow()

    @classmethod
    def install(cls, robot: Robot) -> Tamper:
        """Tamper with ``robot``'s ticked world.

        Raises:
            TypeError: ``robot`` does not tick a world (neither `FakeBase` nor `SimRobot`).
        """
        world = getattr(robot.backend, "world", None)
        if not all(callable(getattr(world, name, None)) for name in _SHADOWED):
            msg = (
                f"holding, silencing or freezing a reading needs a base that ticks a world "
                f"(FakeBase, SimRobot); {robot!r} has none: use disturbances without hold"
            )
            raise TypeError(msg)
        return cls(robot, world)

    def force(self, values: dict[str, object], seconds: float) -> None:
        """The base reads ``values`` for ``seconds``."""
        until = self._robot.time() + seconds
        self._forced.update((key, (value, until)) for key, value in values.items())
        self._shadow()

    def silence(self, key: str, seconds: float) -> None:
        """The base does not publish ``key`` for ``seconds``."""
        self._silent[key] = self._robot.time() + seconds
        self._shadow()

    def freeze_odometry(self, seconds: float) -> None:
        """The odometry stays where it is for ``seconds``."""
        self._odometry = (self._odom_pose(), self._robot.time() + seconds)
        self._shadow()

    def remove(self) -> None:
        """Give the world back its own methods."""
        for name in _SHADOWED:
            vars(self._world).pop(name, None)

    def _shadow(self) -> None:
        """Read the world through the tamper (on the instance: this world alone, this run alone)."""
        self._world.read_sensors, self._world.odom_pose = self._readings, self._odom

    def _rest(self) -> None:
        """Give the world back its own methods while nothing is held, silenced or frozen.

        The tamper then costs the ticks nothing until the next disturbance shadows them again.
        """
        if not (self._forced or self._silent or self._odometry):
            self.remove()

    def _readings(self) -> dict[str, object]:
        readings: dict[str, object] = self._read_sensors()
        now = self._robot.time()
        for key, (value, until) in list(self._forced.items()):
            if until <= now:
                del self._forced[key]
            elif key in readings:
                readings[key] = value
        for key, until in list(self._silent.items()):
            if until <= now:
                del self._silent[key]
            else:
                readings.pop(key, None)
        self._rest()
        return readings

    def _odom(self) -> Pose2D:
        if self._odometry is not None:
            pose, until = self._odometry
            if until > self._robot.time():
                return pose
            self._odometry = None
            self._rest()
        return self._odom_pose()  # type: ignore[no-any-return]
