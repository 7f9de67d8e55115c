"""The sensors of a differential-drive base: one table, read by every base and bridge.

A `Sensor` is a state key and its kind (a flag, or a range in metres). The
table of the standard robot, `SENSORS`, is the one place they are listed:
`pyrobots_aio.testing.FakeBase` computes them, the simulator finds them in its
model (``SimWorld.sensors``: the same table for the shipped robot, a test
pins it), and a ROS 2 profile (``pyrobots_aio.ros2.Profile``) turns them into
topics on both ends, `Ros2Robot` and ``sim-node``. Adding a sensor of a known
kind to the standard robot is a row here and the sensor in
``models/robot.xml``; a sensor the simulator reads in a new way also changes
how ``SimWorld`` reads it (``sim/_models.py`` and ``sim/_world.py``).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

__all__ = ["SENSORS", "Sensor", "SensorKind"]


class SensorKind(enum.Enum):
    """What a sensor's state value is."""

    FLAG = "flag"
    """A bool: a bumper zone pressed, a cliff seen (no floor), the robot on its dock."""
    RANGE = "range"
    """Metres to the nearest thing in view; the sensor's reach when nothing is in it."""


@dataclass(frozen=True, slots=True)
class Sensor:
    """One sensor of a base: its state key, its kind, and for a range its reach and bearing.

    Args:
        key: The state key it publishes (``robot.state.<key>``), e.g. ``"ir_left"``.
        kind: A `SensorKind`.
        reach: For a range, the farthest it sees, in metres (its reading when
            nothing is in range); 0 for a flag.
        bearing: For a range, the direction it looks, in radians counter-clockwise
            from straight ahead; 0 for a flag.

    Raises:
        ValueError: An empty key, or a range without a positive finite reach.

    Examples:
        >>> Sensor("ir_back", SensorKind.RANGE, reach=0.4, bearing=math.pi).resting
        0.4
    """

    key: str
    kind: SensorKind
    reach: float = 0.0
    bearing: float = 0.0

    def __post_init__(self) -> None:
        key: object = self.key  # checked at run time: the annotation promises nothing
        if not isinstance(key, str) or not key:
            msg = f"a sensor's state key must be a non-empty string, got {key!r}"
            raise ValueError(msg)
        if self.kind is SensorKind.RANGE and not 0 < self.reach < math.inf:
            msg = f"the range sensor {key!r} needs a positive reach in metres, got {self.reach!r}"
            raise ValueError(msg)

    @property
    def resting(self) -> bool | float:
        """Its reading when it senses nothing: False for a flag, the reach for a range."""
        return self.reach if self.kind is SensorKind.RANGE else False


_IR_REACH = 0.4  # metres: the shipped model's IR rangefinders' cutoff
_IR_BEARINGS = {  # degrees: where each IR rangefinder looks, as models/robot.xml has them
    "ir_side_left": 65.0,
    "ir_left": 40.0,
    "ir_front_left": 20.0,
    "ir_front_center_left": 5.0,
    "ir_front_center_right": -5.0,
    "ir_front_right": -20.0,
    "ir_right": -45.0,
}
_CLIFFS = ("cliff_front_left", "cliff_front_right", "cliff_side_left", "cliff_side_right")

SENSORS: tuple[Sensor, ...] = (
    Sensor("bumper", SensorKind.FLAG),
    Sensor("bumper_left", SensorKind.FLAG),
    Sensor("bumper_right", SensorKind.FLAG),
    *(
        Sensor(key, SensorKind.RANGE, reach=_IR_REACH, bearing=math.radians(degrees))
        for key, degrees in _IR_BEARINGS.items()
    ),
    *(Sensor(key, SensorKind.FLAG) for key in _CLIFFS),
    Sensor("docked", SensorKind.FLAG),
)
"""The standard robot's sensors (the simulator's, a Create 3's), in the order they are published.

``bumper`` (either side pressed), ``bumper_left``, ``bumper_right``, seven IR
rangefinders ``ir_<position>`` (0.4 m), four cliff sensors
``cliff_<position>`` (True over a cliff) and ``docked``. The odometry's ``v``
and ``w`` come beside them.
"""
