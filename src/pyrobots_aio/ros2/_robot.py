"""`Ros2Robot`: a `DriveBase` over ROS 2, its backend a node speaking a profile.

The motion actions and the random walk run on it unchanged: its
`Ros2Backend` commands ``cmd_vel`` and reads odometry and the sensors from
the topics of a `Profile` (`STANDARD` by default), the very table
``pyrobots-aio sim-node`` publishes through (a real base's driver, remapped,
does as well).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .._exceptions import Ros2Error
from ..motion import SENSORS, Sensor
from ._backend import DOCK_IN_ODOM, Ros2Backend
from ._docking import ProfileDocking
from ._node import Ros2Node, _positive
from ._profiles import STANDARD, Profile
from ._tf import BUILD_TF

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

    from ..motion import Pose2D
    from ._tf import TfBuffer
    from ._topics import Ros2Publisher


class Ros2Robot(ProfileDocking):
    """A differential-drive robot over ROS 2: ``cmd_vel`` out, odometry and sensors in.

    Its backend is a `Ros2Backend`: inside ``async with``, it has a ROS 2 node
    (``robot.ros2``, a `Ros2Node`) and every motion action of `DriveBase` —
    and the random walk — runs on it unchanged. Entering waits until each of
    its topics has spoken once, so the state is complete from the first line.
    The topics are a profile's (`STANDARD` by default, the topics
    ``pyrobots-aio sim-node`` publishes):

    ==========================  ==============================  ========================
    topic (relative: namespace)  type                           becomes
    ==========================  ==============================  ========================
    ``cmd_vel`` (out)           geometry_msgs/msg/Twist         ``drive(v, w)``
    ``odom``                    nav_msgs/msg/Odometry           `odom_pose`, ``v``, ``w``
    ``ir_<position>``           sensor_msgs/msg/Range           ``ir_<position>`` (metres)
    ``bumper``, ``_left/right``  std_msgs/msg/Bool              ``bumper`` ...
    ``cliff_<position>``        std_msgs/msg/Bool               ``cliff_<position>``
    ``docked``                  std_msgs/msg/Bool               ``docked``
    ==========================  ==============================  ========================

    Every topic is remappable: ``topics={"odom": "/robot1/odometry/filtered"}``
    (keys: the roles, ``cmd_vel``, ``odom`` and the state keys above). Inputs are read
    with the ``sensor_data`` QoS (best effort: it matches reliable and
    best-effort publishers alike). An IR reading of +inf (nothing in range, REP
    117) is the sensor's ``max_range``.

    - **Commands** are streamed: a non-zero ``drive(v, w)`` is re-sent with
      each odometry message, so a base with a command timeout (sim-node's,
      a Create 3's) keeps going until ``stop()``.
    - **Control ticks** are odometry messages: each one runs the motion
      controllers; `control_period` is measured from their stamps.
    - **Staleness**: when no odometry came for ``odom_timeout`` seconds, the
      base is stale: ``robot.state.odom_stale`` turns True, a zero ``Twist``
      is sent once, every waiting motion fails with a `MotionError` naming
      the topic and the age, and any further non-zero command is refused
      with that error, until odometry comes back (``odom_stale`` False).
      `odom_age` tells the age at any time.
    - **Resets**: odometry that jumps (a stamp going back, or farther between
      two messages than a base moves: a driver that restarted) is logged as a
      reset and counted in ``robot.state.odom_resets``; the pose goes on from
      where it was, so a motion under way does not act on the jump.
    - **Frames**: ``odom`` is placed at ``odom_in_map`` in ``map`` (a fixed
      localisation; by default the map is the odometry's frame), ``base_link``
      at the odometry pose, and ``dock`` at ``dock`` in ``odom``.
    - **tf**: every other frame comes from ``tf`` and ``tf_static`` (relative
      names: ``/tf`` at the root, ``<namespace>/tf`` under one; roles ``tf``
      and ``tf_static`` remap them): `tf` keeps the latest transform of each
      edge, and ``robot.poses`` resolves the sensor frames a driver (or
      sim-node) broadcasts, as on `SimRobot`. Entering does not wait for tf:
      ``await robot.tf.wait_for_frames("ir_left")`` does.
    - **use_sim_time**: the node's clock follows ``/clock`` (the stamps of what
      it publishes, ``/diagnostics``, `ros_time`); ``robot.time()`` stays the
      event loop's clock — for a base running ``--rate`` times faster than real
      time, run the program on a loop at the same rate.
    - ``/diagnostics``: whether every input is fresh (`Ros2Node`).
    - **Create 3** (``profile="create3"``): bumper and cliff keys come from
      ``hazard_detection``, the IR ranges from ``ir_intensity``, ``docked``
      from ``dock_status``; `dock` and `undock` are goals to the base's own
      ``dock`` and ``undock`` action servers.

    Args:
        namespace: The robot's namespace (``/robot1``): its relative topics live there.
        name: The node's name.
        profile: The topics, types and conversions: a `Profile` or the name of
            one (``"standard"``).
        topics: Topic names by role (see above); those not given keep theirs.
        sensors: The sensors to read (default: the standard robot's,
            `pyrobots_aio.motion.SENSORS`).
        odom_timeout: Seconds without odometry before the base is stale.
        connect_timeout: Seconds entering waits for every topic's first message.
        odom_in_map: Where the ``odom`` frame lies in ``map``, ``(x, y, yaw)``.
        dock: Where the dock's frame lies in ``odom`` (default `DOCK_IN_ODOM`:
            the robot starts on its dock).
        tf: Listen to tf: True, False, or None (default) for "if ``tf2_msgs``
            can be imported" (``pyrobots-aio ros2 interfaces build tf2_msgs``).
        use_sim_time: The node's clock follows ``/clock``.
        domain_id: The DDS domain; default: ``ROS_DOMAIN_ID``.
        diagnostics_period: Seconds between two ``/diagnostics`` messages (None: none).
        **options: `DriveBase` and `Robot` options (``stall_timeout``, ``instruments`` ...).

    Raises:
        Ros2UnavailableError: rclpy cannot be imported (install the ``ros2`` extra).
        Ros2NameError: ROS 2 rejects the name, the namespace or a topic (its reason quoted).

    Examples:
        >>> from pyrobots_aio.ros2 import Ros2Robot  # doctest: +SKIP
        >>> from pyrobots_aio.sim.random_walk import random_walk
        >>> async def main() -> None:
        ...     async with Ros2Robot(namespace="/robot1") as robot:  # beside a sim-node
        ...         await random_walk(robot, duration=60)
    """

    def __init__(
        self,
        *,
        namespace: str = "/",
        name: str = "pyrobots_aio",
        profile: Profile | str = STANDARD,
        topics: Mapping[str, str] | None = None,
        sensors: Iterable[Sensor] = SENSORS,
        odom_timeout: float = 0.5,
        connect_timeout: float = 30.0,
        odom_in_map: Pose2D = (0.0, 0.0, 0.0),
        dock: Pose2D = DOCK_IN_ODOM,
        tf: bool | None = None,
        use_sim_time: bool = False,
        domain_id: int | None = None,
        diagnostics_period: float | None = 1.0,
        **options: Any,
    ) -> None:
        node = Ros2Node(
            name,
            namespace=namespace,
            use_sim_time=use_sim_time,
            domain_id=domain_id,
            diagnostics_period=diagnostics_period,
            stale_after=_positive("odom_timeout", odom_timeout),
        )
        ros = Ros2Backend(
            node,
            profile=profile,
            sensors=sensors,
            topics=topics,
            odom_timeout=odom_timeout,
            connect_timeout=connect_timeout,
            odom_in_map=odom_in_map,
            dock=dock,
            tf=tf,
        )
        super().__init__(backend=ros, **options)
        self.ros = ros

    @property
    def ros2(self) -> Ros2Node:
        """The robot's ROS 2 node (its backend's): topics, services, goals, diagnostics."""
        return self.ros.node

    @property
    def tf(self) -> TfBuffer:
        """The frames heard on ``tf`` and ``tf_static`` (its backend's `TfBuffer`).

        Raises:
            Ros2Error: The robot is not running, or listens to no tf (``tf=False``,
                or ``tf2_msgs`` missing).
        """
        tf = self.ros.tf
        if tf is None or not self.is_running:
            msg = (
                f"{self!r} has no tf buffer: it exists inside 'async with' when tf2_msgs "
                f"imports (build it with: {BUILD_TF}) and tf is not False"
            )
            raise Ros2Error(msg)
        return tf

    @property
    def cmd_vel(self) -> Ros2Publisher[Any]:
        """The ``cmd_vel`` publisher (``await robot.cmd_vel.wait_for_subscribers()`` ...).

        Raises:
            Ros2Error: The robot is not running.
        """
        return self.ros.cmd_vel

    def odom_age(self) -> float | None:
        """Seconds (robot clock) since the last odometry message; None before any."""
        return self.ros.odom_age()

    def ros_time(self) -> float:
        """The node's clock in seconds: ``/clock`` under ``use_sim_time``, else the system's."""
        nanoseconds: int = self.ros2.node.get_clock().now().nanoseconds
        return nanoseconds / 1e9

    def __repr__(self) -> str:
        state = "running" if self.is_running else "stopped"
        return f"<Ros2Robot {self.ros2.full_name} {state}>"
