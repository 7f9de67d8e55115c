"""`Ros2Robot`: a `DriveBase` over standard ROS 2 messages.

The motion actions and the random walk run on it unchanged: it commands
``cmd_vel`` and reads odometry, IR ranges, bumper, cliff and dock state from
topics, in the types ``pyrobots-aio sim-node`` publishes (a real base's
driver, remapped, does as well). Odometry is its heartbeat: each message is a
control tick, and when odometry stops coming the base goes stale, stops, and
every motion fails with a `MotionError` naming the topic and the age.
"""

from __future__ import annotations

import asyncio
import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._exceptions import MotionError, Ros2Error
from ..motion import Controllers, DriveBase
from ._node import _positive, attach_ros2
from ._rclpy import check_message_type, check_topic, rclpy_module

if TYPE_CHECKING:
    from collections.abc import Callable, Collection, Iterable, Mapping

    from numpy.typing import NDArray

    from ..motion import Pose2D
    from ._node import Ros2Node
    from ._topics import Ros2Publisher, Ros2Subscription

_log = logging.getLogger("pyrobots_aio.ros2")

IR_SENSORS = (
    "ir_side_left",
    "ir_left",
    "ir_front_left",
    "ir_front_center_left",
    "ir_front_center_right",
    "ir_front_right",
    "ir_right",
)
"""The IR rangefinders `Ros2Robot` reads by default (those of ``sim-node``), one topic each."""
CLIFF_SENSORS = ("cliff_front_left", "cliff_front_right", "cliff_side_left", "cliff_side_right")
"""The cliff sensors `Ros2Robot` reads by default (those of ``sim-node``), one topic each."""
FLAGS = ("bumper", "bumper_left", "bumper_right", "docked")
"""The ``std_msgs/Bool`` topics every `Ros2Robot` reads (besides the cliff sensors)."""
DOCK_IN_ODOM: Pose2D = (-0.172, 0.0, 0.0)
"""Where the dock's frame is in ``odom`` for a base that starts on its dock (a Create 3).

The odometry starts at the robot's centre, 0.172 m in front of the dock's face.
"""
_FIRST_PERIOD = 0.02  # seconds: the control period assumed until odometry tells


def _pose2d(name: str, value: object) -> Pose2D:
    if (
        isinstance(value, tuple | list)
        and len(value) == 3
        and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
    ):
        x, y, yaw = value
        return float(x), float(y), float(yaw)
    msg = f"{name} must be a planar pose (x, y, yaw) of finite numbers, got {value!r}"
    raise ValueError(msg)


def _compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """Pose ``b`` (given in the frame that is at ``a``) expressed where ``a`` is given."""
    ax, ay, ayaw = a
    bx, by, byaw = b
    c, s = math.cos(ayaw), math.sin(ayaw)
    return ax + c * bx - s * by, ay + s * bx + c * by, math.remainder(ayaw + byaw, math.tau)


def _yaw(q: Any) -> float:
    """The yaw of a ``geometry_msgs/Quaternion``."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _float32(value: float) -> float:
    """A float32 field as the decimal it was written as (``0.4``, not ``0.4000000059604645``)."""
    return float(f"{value:.7g}")


def _range(message: Any) -> float:
    """A ``Range`` reading in metres; the sensor's range when nothing is in it (+inf, REP 117)."""
    reading, limit = float(message.range), _float32(message.max_range)
    return limit if not math.isfinite(reading) or reading > limit else _float32(reading)


class _Frames:
    """``odom``, ``base_link`` and ``dock`` of a `Ros2Robot`, placed in ``map``."""

    FRAMES = ("odom", "base_link", "dock")

    def __init__(self, robot: Ros2Robot) -> None:
        self._robot = robot

    def get_transform(self, frame: str) -> NDArray[np.float64]:
        robot = self._robot
        if frame == "odom":
            x, y, yaw = robot.odom_in_map
        elif frame == "base_link":
            x, y, yaw = robot.map_pose()
        elif frame == "dock":
            x, y, yaw = _compose(robot.odom_in_map, robot.dock_in_odom)
        else:
            from .. import UnknownFrameError

            msg = f"unknown frame {frame!r}; known frames: {sorted(self.FRAMES)}"
            raise UnknownFrameError(msg)
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0, 0, 0, 1.0]])

    def frames(self) -> Collection[str]:
        return self.FRAMES


class Ros2Robot(DriveBase):
    """A differential-drive robot over ROS 2: ``cmd_vel`` out, odometry and sensors in.

    Inside ``async with``, it has a ROS 2 node (``robot.ros2``, a `Ros2Node`)
    and every motion action of `DriveBase` — and the random walk — runs on it
    unchanged. Entering waits until each of its topics has spoken once, so
    the state is complete from the first line.

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
    (keys: ``cmd_vel``, ``odom`` and the state keys above). Inputs are read
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
    - **Frames**: ``odom`` is placed at ``odom_in_map`` in ``map`` (a fixed
      localisation; by default the map is the odometry's frame), ``base_link``
      at the odometry pose, and ``dock`` at ``dock`` in ``odom``.
    - **use_sim_time**: the node's clock follows ``/clock`` (the stamps of what
      it publishes, ``/diagnostics``, `ros_time`); ``robot.time()`` stays the
      event loop's clock — for a base running ``--rate`` times faster than real
      time, run the program on a loop at the same rate.
    - ``/diagnostics``: whether every input is fresh (`Ros2Node`).

    Args:
        namespace: The robot's namespace (``/robot1``): its relative topics live there.
        name: The node's name.
        topics: Topic names by role (see above); those not given keep theirs.
        ir_sensors: The IR rangefinders' state keys (one topic each).
        cliff_sensors: The cliff sensors' state keys (one topic each).
        odom_timeout: Seconds without odometry before the base is stale.
        connect_timeout: Seconds entering waits for every topic's first message.
        odom_in_map: Where the ``odom`` frame lies in ``map``, ``(x, y, yaw)``.
        dock: Where the dock's frame lies in ``odom`` (default `DOCK_IN_ODOM`:
            the robot starts on its dock).
        use_sim_time: The node's clock follows ``/clock``.
        domain_id: The DDS domain; default: ``ROS_DOMAIN_ID``.
        diagnostics_period: Seconds between two ``/diagnostics`` messages (None: none).
        **options: `DriveBase` and `Robot` options (``stall_timeout``, ``instruments`` ...).

    Raises:
        Ros2UnavailableError: rclpy cannot be imported (install the ``ros2`` extra).
        Ros2NameError: ROS 2 rejects the name, the namespace or a topic (its reason quoted).

    Example:
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
        topics: Mapping[str, str] | None = None,
        ir_sensors: Iterable[str] = IR_SENSORS,
        cliff_sensors: Iterable[str] = CLIFF_SENSORS,
        odom_timeout: float = 0.5,
        connect_timeout: float = 30.0,
        odom_in_map: Pose2D = (0.0, 0.0, 0.0),
        dock: Pose2D = DOCK_IN_ODOM,
        use_sim_time: bool = False,
        domain_id: int | None = None,
        diagnostics_period: float | None = 1.0,
        **options: Any,
    ) -> None:
        self._ir = tuple(ir_sensors)
        self._cliff = tuple(cliff_sensors)
        self.topics = self._topic_names(topics)
        self.odom_timeout = _positive("odom_timeout", odom_timeout)
        self.connect_timeout = _positive("connect_timeout", connect_timeout)
        self.odom_in_map = _pose2d("odom_in_map", odom_in_map)
        self.dock_in_odom = _pose2d("dock", dock)
        super().__init__(**options)
        self.ros2: Ros2Node = attach_ros2(
            self,
            name,
            namespace=namespace,
            use_sim_time=use_sim_time,
            domain_id=domain_id,
            diagnostics_period=diagnostics_period,
            stale_after=self.odom_timeout,
        )
        self.poses.add_frame_provider(_Frames(self))
        self._controllers = Controllers()
        self._odom: Pose2D = (0.0, 0.0, 0.0)
        self._period = _FIRST_PERIOD
        self._stamp: float | None = None
        self._last_odom: float | None = None
        self._stale_timer: asyncio.TimerHandle | None = None
        self._stale: MotionError | None = None
        self._command: tuple[float, float] = (0.0, 0.0)
        self._sent = False
        self._cmd: Ros2Publisher[Any] | None = None
        # Imported and their type supports loaded now, before the robot runs: that takes a
        # tenth of a second, which would block the running loop.
        self._types = tuple(
            check_message_type(getattr(rclpy_module(f"{package}.msg"), kind))
            for package, kind in (
                ("geometry_msgs", "Twist"),
                ("nav_msgs", "Odometry"),
                ("sensor_msgs", "Range"),
                ("std_msgs", "Bool"),
            )
        )
        self._subscriptions: list[Ros2Subscription] = []

    def _topic_names(self, topics: Mapping[str, str] | None) -> dict[str, str]:
        names = {key: key for key in ("cmd_vel", "odom", *FLAGS, *self._ir, *self._cliff)}
        for sensor in (*self._ir, *self._cliff):
            if not isinstance(sensor, str) or not sensor:
                msg = f"a sensor's state key must be a non-empty string, got {sensor!r}"
                raise ValueError(msg)
        unknown = sorted(set(topics or {}) - set(names))
        if unknown:
            msg = f"unknown topic roles {unknown} in topics=; known roles: {sorted(names)}"
            raise ValueError(msg)
        names.update(topics or {})
        for role, topic in names.items():
            check_topic(topic, f"{role} topic name")
        return names

    # -- the DriveBase seam ---------------------------------------------------------

    @property
    def control_period(self) -> float:
        """Seconds between two odometry messages (measured from their stamps)."""
        return self._period

    def odom_pose(self) -> Pose2D:
        """The latest odometry pose ``(x, y, yaw)``, in the ``odom`` frame."""
        return self._odom

    def map_pose(self) -> Pose2D:
        """The odometry pose placed in ``map`` through ``odom_in_map``."""
        return _compose(self.odom_in_map, self._odom)

    async def control(self, step: Callable[[], bool]) -> None:
        """Call ``step()`` after each odometry message until it returns True.

        Raises:
            MotionError: Odometry is stale (now, or while waiting).
        """
        if self._stale is not None:
            raise self._stale
        await self._controllers.control(step)

    def _set_velocity(self, v: float, w: float) -> None:
        if self._stale is not None:
            if v or w:
                raise self._stale
            self._command = (0.0, 0.0)
            return  # the zero Twist went out when odometry went stale
        self._command = (v, w)
        self._send()

    # -- facts ----------------------------------------------------------------------

    @property
    def cmd_vel(self) -> Ros2Publisher[Any]:
        """The ``cmd_vel`` publisher (``await robot.cmd_vel.wait_for_subscribers()`` ...).

        Raises:
            Ros2Error: The robot is not running.
        """
        if self._cmd is None:
            msg = f"{self!r} is not running: its cmd_vel publisher exists inside 'async with'"
            raise Ros2Error(msg)
        return self._cmd

    def odom_age(self) -> float | None:
        """Seconds (robot clock) since the last odometry message; None before any."""
        if self._last_odom is None or not self.is_running:
            return None
        return self.time() - self._last_odom

    def ros_time(self) -> float:
        """The node's clock in seconds: ``/clock`` under ``use_sim_time``, else the system's."""
        nanoseconds: int = self.ros2.node.get_clock().now().nanoseconds
        return nanoseconds / 1e9

    # -- lifecycle ------------------------------------------------------------------

    async def _start(self) -> None:
        await super()._start()  # the node is up
        try:
            await self._connect()
        except BaseException:
            await self._disconnect()
            await super()._stop()
            raise

    async def _stop(self) -> None:
        try:
            self.stop()
            await self._disconnect()
        finally:
            await super()._stop()

    async def _connect(self) -> None:
        twist, odometry, ray, flag = self._types
        ros2, topics = self.ros2, self.topics
        self._cmd = ros2.publisher(topics["cmd_vel"], twist)
        subs = [
            ros2.subscribe(
                topics["odom"],
                odometry,
                self._odometry,
                callback=self._tick,
                qos="sensor_data",
            )
        ]
        subs += [
            ros2.subscribe(topics[key], ray, lambda m, k=key: {k: _range(m)}, qos="sensor_data")
            for key in self._ir
        ]
        subs += [
            ros2.subscribe(topics[key], flag, {key: "data"}, qos="sensor_data")
            for key in (*FLAGS, *self._cliff)
        ]
        self._subscriptions = subs
        try:
            async with asyncio.timeout(self.connect_timeout):
                await asyncio.gather(*(self._first(sub) for sub in subs))
        except TimeoutError:
            silent = [sub.topic for sub in subs if sub.received == 0]
            msg = (
                f"no message in {self.connect_timeout:g} s on {', '.join(silent)}: is the "
                f"robot's driver (or 'pyrobots-aio sim-node --namespace {ros2.namespace}') "
                f"running in domain {ros2.domain_id}? (connect_timeout= waits longer)"
            )
            raise Ros2Error(msg) from None
        self.state.update(odom_stale=False)

    @property
    def _odom_topic(self) -> str:
        return self._subscriptions[0].topic if self._subscriptions else self.topics["odom"]

    @staticmethod
    async def _first(sub: Ros2Subscription) -> None:
        if sub.received == 0:
            await sub.wait_for_message()

    async def _disconnect(self) -> None:
        if self._stale_timer is not None:
            self._stale_timer.cancel()
            self._stale_timer = None
        self._controllers.cancel()
        for sub in self._subscriptions:
            sub.close()
        self._subscriptions = []
        self._cmd = None
        self._last_odom = self._stamp = None
        self._stale = None

    # -- messages (on the loop) -----------------------------------------------------

    def _odometry(self, message: Any) -> Mapping[str, object]:
        pose = message.pose.pose
        self._odom = (pose.position.x, pose.position.y, _yaw(pose.orientation))
        twist = message.twist.twist
        return {"v": twist.linear.x, "w": twist.angular.z}

    def _tick(self, message: Any) -> None:
        """An odometry message: fresh again, a control tick, the command re-sent."""
        now = self.time()
        stamp = message.header.stamp.sec + message.header.stamp.nanosec * 1e-9 or now
        if self._stamp is not None and 0.0 < stamp - self._stamp < 1.0:
            self._period += 0.1 * (stamp - self._stamp - self._period)
        self._stamp, self._last_odom = stamp, now
        if self._stale is not None:
            _log.info("odometry on %s is back: the base is live again", self._odom_topic)
            self._stale = None
            self.state.update(odom_stale=False)
        if self._stale_timer is None:
            self._arm(now + self.odom_timeout)
        self._sent = False
        self._controllers.run()
        if not self._sent and self._command != (0.0, 0.0):
            self._send()

    def _arm(self, when: float) -> None:
        self._stale_timer = asyncio.get_running_loop().call_at(when, self._check_odom, when)

    def _check_odom(self, when: float) -> None:
        """The odometry timer: stale if nothing came for ``odom_timeout`` (the loop's lag aside)."""
        self._stale_timer = None
        if self._last_odom is None:
            return
        due = self._last_odom + self.odom_timeout
        now = self.time()
        if now < due:
            self._arm(due)
            return
        if now - when > self.odom_timeout / 2:
            # The loop itself was held up (blocking code): the ROS thread may have been
            # starved of the GIL too. Odometry gets a fresh window before it counts as stale.
            _log.debug(
                "odometry check %.3f s late: the loop was blocked; looking again", now - when
            )
            self._arm(now + self.odom_timeout)
            return
        self._go_stale(now)

    def _go_stale(self, now: float) -> None:
        assert self._last_odom is not None  # called after odometry came
        topic = self._cmd.topic if self._cmd is not None else self.topics["cmd_vel"]
        age = now - self._last_odom
        error = MotionError(
            f"odometry on {self._odom_topic} is stale: no message for {age:.2f} s "
            f"(odom_timeout {self.odom_timeout:g} s); the base was stopped (zero Twist on "
            f"{topic}) and refuses to move until odometry comes back — is its driver running?"
        )
        _log.warning("%s", error)
        self._command = (0.0, 0.0)
        self._send()
        self._stale = error
        self.state.update(odom_stale=True)
        self._controllers.fail(error)

    def _send(self) -> None:
        if self._cmd is None:
            return
        twist = self._types[0]()
        twist.linear.x, twist.angular.z = self._command
        self._cmd.publish(twist)
        self._sent = True

    def __repr__(self) -> str:
        state = "running" if self.is_running else "stopped"
        return f"<Ros2Robot {self.ros2.full_name} {state}>"
