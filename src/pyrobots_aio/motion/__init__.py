"""One motion layer for every differential-drive base: `DriveBase` and its actions.

A base (the simulator's `pyrobots_aio.sim.SimRobot`, a ROS 2 robot, or the
in-memory `pyrobots_aio.testing.FakeBase`) is a `DriveBackend` that a
`DriveBase` holds: a velocity command, odometry and a per-tick control hook
(`Controllers`; `TickingBackend` ticks a simulated world), and the sensors
of one table (`SENSORS`). The motion
actions (``drive_distance``, ``rotate_angle``, ``navigate_to``, ``dock``,
``undock``) and the random walk (`pyrobots_aio.sim.random_walk`) are written
once against it, so the same behaviour runs on each, stall detection
(`StallWatch`, `STALL_TIMEOUT`) included.
"""

from ._backend import DriveBackend as DriveBackend
from ._backend import Pose2D as Pose2D
from ._base import ANGLE_TOLERANCE as ANGLE_TOLERANCE
from ._base import DISTANCE_TOLERANCE as DISTANCE_TOLERANCE
from ._base import DOCK_APPROACH as DOCK_APPROACH
from ._base import UNDOCK_DISTANCE as UNDOCK_DISTANCE
from ._base import WHEELS as WHEELS
from ._base import DriveBase as DriveBase
from ._control import Controllers as Controllers
from ._math import MAX_DISTANCE as MAX_DISTANCE
from ._math import MAX_TURN as MAX_TURN
from ._math import limit_speeds as limit_speeds
from ._math import wrap_angle as wrap_angle
from ._sensors import SENSORS as SENSORS
from ._sensors import Sensor as Sensor
from ._sensors import SensorKind as SensorKind
from ._stall import STALL_TIMEOUT as STALL_TIMEOUT
from ._stall import STALL_TRAVEL as STALL_TRAVEL
from ._stall import STALL_TURN as STALL_TURN
from ._stall import StallWatch as StallWatch
from ._ticking import TICKS_PER_TURN as TICKS_PER_TURN
from ._ticking import TickedWorld as TickedWorld
from ._ticking import TickingBackend as TickingBackend

__all__ = [
    "ANGLE_TOLERANCE",
    "DISTANCE_TOLERANCE",
    "DOCK_APPROACH",
    "MAX_DISTANCE",
    "MAX_TURN",
    "SENSORS",
    "STALL_TIMEOUT",
    "STALL_TRAVEL",
    "STALL_TURN",
    "TICKS_PER_TURN",
    "UNDOCK_DISTANCE",
    "WHEELS",
    "Controllers",
    "DriveBackend",
    "DriveBase",
    "Pose2D",
    "Sensor",
    "SensorKind",
    "StallWatch",
    "TickedWorld",
    "TickingBackend",
    "limit_speeds",
    "wrap_angle",
]
