"""One motion layer for every differential-drive base: `DriveBase` and its actions.

A base (the simulator's `pyrobots_aio.sim.SimRobot`, a ROS 2 robot, or the
in-memory `pyrobots_aio.testing.FakeBase`) is a `DriveBackend` that a
`DriveBase` holds: a velocity command, odometry and a per-tick control hook
(`Controllers`; `TickingBackend` ticks a simulated world), and the sensors
of one table (`SENSORS`). The motion
actions (``drive_distance``, ``rotate_angle``, ``navigate_to``, ``dock``,
``undock``) and the random walk (`pyrobots_aio.sim.random_walk`) are written
once against it, so the same behaviour runs on each, stall detection
(`STALL_TIMEOUT`) included; `DISTANCE_TOLERANCE` and `ANGLE_TOLERANCE` say how
close to their goal they stop, and `WHEELS` is the resource they hold.
"""

from ..poses import Pose2D as Pose2D
from ._backend import DriveBackend as DriveBackend
from ._base import ANGLE_TOLERANCE as ANGLE_TOLERANCE
from ._base import DISTANCE_TOLERANCE as DISTANCE_TOLERANCE
from ._base import WHEELS as WHEELS
from ._base import DriveBase as DriveBase
from ._control import Controllers as Controllers
from ._sensors import SENSORS as SENSORS
from ._sensors import Sensor as Sensor
from ._sensors import SensorKind as SensorKind
from ._stall import STALL_TIMEOUT as STALL_TIMEOUT
from ._ticking import TickedWorld as TickedWorld
from ._ticking import TickingBackend as TickingBackend

__all__ = [
    "ANGLE_TOLERANCE",
    "DISTANCE_TOLERANCE",
    "SENSORS",
    "STALL_TIMEOUT",
    "WHEELS",
    "Controllers",
    "DriveBackend",
    "DriveBase",
    "Pose2D",
    "Sensor",
    "SensorKind",
    "TickedWorld",
    "TickingBackend",
]
