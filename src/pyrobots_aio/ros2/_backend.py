"""`Ros2Backend`: a drive backend over ROS 2, a node speaking a profile.

It commands ``cmd_vel`` and reads odometry and the sensors from the topics
of a `Profile` (`STANDARD` by default), the very table ``pyrobots-aio
sim-node`` publishes through (a real base's driver, remapped, does as well).
Odometry is its heartbeat: each message is a control tick, and when odometry
stops coming the base goes stale, stops, and every motion fails with a
`MotionError` naming the topic and the age.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._exceptions import MotionError, Ros2Error, Ros2UnavailableError
from ..motion import SENSORS, Controllers, Sensor
from ._node import _positive
from ._profiles import STANDARD, Odometry, Profile, profile_named
from ._rclpy import check_topic
from ._resets import OdometryResets, compose
from ._tf import (
    BUILD_TF,
    TF,
    TF_STATIC,
    TfBuffer,
    place_through_tf,
    planar_matrix,
    tf_message_class,
    tf_qos,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Collection, Iterable, Mapping

    from numpy.typing import NDArray

    from ..motion import Pose2D
    from ..robot import Robot
    from ._node import Ros2Node
    from ._profiles import Topic
    from ._topics import Ros2Publisher, Ros2Subscription

_log = logging.getLogger("pyrobots_aio.ros2")

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


def _sensors(sensors: Iterable[Sensor]) -> tuple[Sensor, ...]:
    table = tuple(sensors)
    strays: list[object] = [s for s in table if not isinstance(s, Sensor)]
    if strays:
        msg = f"sensors must be Sensor records (pyrobots_aio.motion.Sensor), got {strays[0]!r}"
        raise TypeError(msg)
    return table


def _tf_type(tf: bool | None) -> type | None:
    """The tf message class if tf is on; None if off (or, for None, if tf2_msgs is missing)."""
    if tf is False:
        return None
    try:
        return tf_message_class()
    except Ros2UnavailableError:
        if tf:
            raise
        _log.debug("no tf: tf2_msgs cannot be imported (%s builds it)", BUILD_TF)
        return None


class _Frames:
    """``odom``, ``base_link`` and ``dock`` of a `Ros2Backend`, placed in ``map``; tf's besides.

    A frame tf broadcasts (a sensor's, under ``base_link``) is placed through
    the backend's `TfBuffer`, its chain completed by these three.
    """

    FRAMES = ("odom", "base_link", "dock")

    def __init__(self, backend: Ros2Backend) -> None:
        self._backend = backend

    def get_transform(self, frame: str) -> NDArray[np.float64]:
        backend = self._backend
        if frame == "odom":
            x, y, yaw = backend.odom_in_map
        elif frame == "base_link":
            x, y, yaw = backend.map_pose()
        elif frame == "dock":
            x, y, yaw = compose(backend.odom_in_map, backend.dock_in_odom)
        else:
            return place_through_tf(backend.tf, frame, self.get_transform, self.frames())
        return planar_matrix(x, y, yaw)

    def frames(self) -> Collection[str]:
        tf = self._backend.tf
        return self.FRAMES if tf is None else (*self.FRAMES, *sorted(tf.frames()))


class Ros2Backend:
    """A `pyrobots_aio.motion.DriveBackend` over ROS 2: a node, and a profile's topics.

    Starting it brings its node up, then subscribes to the profile's
    odometry and sensor topics and waits until each has spoken once (so the
    state is complete from the first line); stopping it sends a zero command,
    closes them and stops the node.

    Args:
        node: Its `Ros2Node` (it starts and stops it).
        profile: The topics, types and conversions (a `Profile`, or a name
            in `PROFILES`); default `STANDARD`.
        sensors: The sensors to read (default: the standard robot's,
            `pyrobots_aio.motion.SENSORS`).
        topics: Topic names by role, replacing the profile's.
        odom_timeout: Seconds without odometry before the base is stale.
        connect_timeout: Seconds starting waits for every topic's first message.
        odom_in_map: Where the ``odom`` frame lies in ``map``, ``(x, y, yaw)``.
        dock: Where the dock's frame lies in ``odom``.
        tf: Keep a `TfBuffer` fed by ``tf`` and ``tf_static`` (`tf`): True,
            False, or None (default) for "if ``tf2_msgs`` can be imported".

    Raises:
        Ros2UnavailableError: A message type cannot be imported.
        Ros2NameError: ROS 2 rejects a topic name (its reason quoted).
        ValueError: An unknown profile or topic role, or a bad number or pose.
    """

    def __init__(
        self,
        node: Ros2Node,
        *,
        profile: Profile | str = STANDARD,
        sensors: Iterable[Sensor] = SENSORS,
        topics: Mapping[str, str] | None = None,
        odom_timeout: float = 0.5,
        connect_timeout: float = 30.0,
        odom_in_map: Pose2D = (0.0, 0.0, 0.0),
        dock: Pose2D = DOCK_IN_ODOM,
        tf: bool | None = None,
    ) -> None:
        self.node = node
        self.profile = profile_named(profile)
        self._sensors = _sensors(sensors)
        self._inputs = self.profile.sensors(self._sensors)
        self._tf_type = _tf_type(tf)
        self.topics = self._topic_names(topics)
        self.odom_timeout = _positive("odom_timeout", odom_timeout)
        self.connect_timeout = _positive("connect_timeout", connect_timeout)
        self.odom_in_map = _pose2d("odom_in_map", odom_in_map)
        self.dock_in_odom = _pose2d("dock", dock)
        self._frames = _Frames(self)
        self._controllers = Controllers()
        self._robot: Robot | None = None
        self._running = contextlib.AsyncExitStack()
        self._odom: Pose2D = (0.0, 0.0, 0.0)
        # Beyond twice the timeout the base went stale and was told to stop.
        self._resets = OdometryResets(
            self.topics[self.profile.odometry.role], horizon=2 * self.odom_timeout
        )
        self._period = _FIRST_PERIOD
        self._reading: Odometry | None = None  # the odometry message being delivered
        self._stamp: float | None = None
        self._last_odom: float | None = None
        self._stale_timer: asyncio.TimerHandle | None = None
        self._stale: MotionError | None = None
        self._command: tuple[float, float] = (0.0, 0.0)
        self._sent = False
        self._cmd: Ros2Publisher[Any] | None = None
        # Imported and their type supports loaded now, before the robot runs: that takes a
        # tenth of a second, which would block the running loop.
        self._types = {topic.role: topic.message_class() for topic in self._topics()}
        self._subscriptions: list[Ros2Subscription] = []
        self.tf: TfBuffer | None = None
        """The frames heard on ``tf`` and ``tf_static`` (None: tf is off); reset at each start."""

    def _topics(self) -> tuple[Topic[Any], ...]:
        """Every topic it uses: the command, the odometry, the sensors'."""
        return (self.profile.command, self.profile.odometry, *self._inputs)

    def _topic_names(self, topics: Mapping[str, str] | None) -> dict[str, str]:
        names = {topic.role: topic.name for topic in self._topics()}
        if self._tf_type is not None:
            names.update({TF: TF, TF_STATIC: TF_STATIC})
        unknown = sorted(set(topics or {}) - set(names))
        if unknown:
            msg = f"unknown topic roles {unknown} in topics=; known roles: {sorted(names)}"
            raise ValueError(msg)
        names.update(topics or {})
        for role, topic in names.items():
            check_topic(topic, f"{role} topic name")
        return names

    # -- DriveBackend -----------------------------------------------------------------

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The sensors it reads."""
        return self._sensors

    @property
    def frames(self) -> _Frames:
        """``odom`` at ``odom_in_map``, ``base_link`` at the odometry, ``dock`` in ``odom``."""
        return self._frames

    @property
    def control_period(self) -> float:
        """Seconds between two odometry messages (measured from their stamps)."""
        return self._period

    def odom_pose(self) -> Pose2D:
        """The latest odometry pose ``(x, y, yaw)``, in the ``odom`` frame."""
        return self._odom

    def map_pose(self) -> Pose2D:
        """The odometry pose placed in ``map`` through ``odom_in_map``."""
        return compose(self.odom_in_map, self._odom)

    async def control(self, step: Callable[[], bool]) -> None:
        """Call ``step()`` after each odometry message until it returns True.

        Raises:
            MotionError: Odometry is stale (now, or while waiting).
        """
        if self._stale is not None:
            raise self._stale
        await self._controllers.control(step)

    def set_velocity(self, v: float, w: float) -> None:
        """Send the command now, and again with each odometry message while it is not zero.

        Raises:
            MotionError: Odometry is stale and the command is not zero.
        """
        if self._stale is not None:
            if v or w:
                raise self._stale
            self._command = (0.0, 0.0)
            return  # the zero command went out when odometry went stale
        self._command = (v, w)
        self._send()

    async def start(self, robot: Robot) -> None:
        """Bring the node up, subscribe, and wait for every topic's first message."""
        async with contextlib.AsyncExitStack() as stack:
            await self.node.start(robot)
            stack.push_async_callback(self.node.stop)
            self._robot = robot
            stack.push_async_callback(self._disconnect)
            await self._connect()
            self._running = stack.pop_all()

    async def stop(self) -> None:
        """Send a zero command, close the topics, stop the node."""
        running, self._running = self._running, contextlib.AsyncExitStack()
        async with running:
            self.set_velocity(0.0, 0.0)

    # -- facts --------------------------------------------------------------------------

    @property
    def cmd_vel(self) -> Ros2Publisher[Any]:
        """The command's publisher (``await backend.cmd_vel.wait_for_subscribers()`` ...).

        Raises:
            Ros2Error: The backend is not running.
        """
        if self._cmd is None:
            msg = f"{self!r} is not running: its cmd_vel publisher exists inside 'async with'"
            raise Ros2Error(msg)
        return self._cmd

    def odom_age(self) -> float | None:
        """Seconds (robot clock) since the last odometry message; None before any."""
        if self._last_odom is None or self._robot is None or not self._robot.is_running:
            return None
        return self._robot.time() - self._last_odom

    # -- connecting -------------------------------------------------------------------

    async def _connect(self) -> None:
        ros2, topics, types, odometry = self.node, self.topics, self._types, self.profile.odometry
        command = self.profile.command
        self._cmd = ros2.publisher(topics[command.role], types[command.role], qos=command.qos)
        subs = [
            ros2.subscribe(
                topics[odometry.role],
                types[odometry.role],
                self._on_odometry,
                callback=self._tick,
                qos="sensor_data",
            )
        ]
        subs += [
            ros2.subscribe(topics[t.role], types[t.role], t.decode, qos="sensor_data")
            for t in self._inputs
        ]
        self._subscriptions = [*subs, *self._listen_to_tf()]
        self._resets.topic = subs[0].topic
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
        assert self._robot is not None  # started
        self._robot.state.update(odom_stale=False, odom_resets=0)

    def _listen_to_tf(self) -> list[Ros2Subscription]:
        """A fresh `TfBuffer` fed by ``tf`` and ``tf_static`` (not waited for: tf is optional)."""
        if self._tf_type is None:
            return []
        tf = self.tf = TfBuffer(_Frames.FRAMES)
        return [
            self.node.subscribe(
                self.topics[name], self._tf_type, callback=tf.receive, qos=tf_qos(static=static)
            )
            for name, static in ((TF, False), (TF_STATIC, True))
        ]

    @property
    def _odom_topic(self) -> str:
        if self._subscriptions:
            return self._subscriptions[0].topic
        return self.topics[self.profile.odometry.role]

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
        self._resets.clear()

    # -- messages (on the loop) -----------------------------------------------------

    def _on_odometry(self, message: Any) -> Mapping[str, object]:
        reading = self._reading = self.profile.odometry.decode(message)
        resets = self._resets.count
        assert self._robot is not None  # running
        self._odom = self._resets.pose(reading, self._odom, self._robot.time())
        if self._resets.count != resets:
            return {"v": reading.v, "w": reading.w, "odom_resets": self._resets.count}
        return {"v": reading.v, "w": reading.w}

    def _tick(self, _message: Any) -> None:
        """An odometry message: fresh again, a control tick, the command re-sent."""
        assert self._robot is not None  # running
        assert self._reading is not None  # decoded by _on_odometry, just before
        now = self._robot.time()
        stamp = self._reading.stamp or now
        if self._stamp is not None and 0.0 < stamp - self._stamp < 1.0:
            self._period += 0.1 * (stamp - self._stamp - self._period)
        self._stamp, self._last_odom = stamp, now
        if self._stale is not None:
            _log.info("odometry on %s is back: the base is live again", self._odom_topic)
            self._stale = None
            self._robot.state.update(odom_stale=False)
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
        if self._last_odom is None or self._robot is None:
            return
        due = self._last_odom + self.odom_timeout
        now = self._robot.time()
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
        assert self._robot is not None
        command = self.profile.command
        topic = self._cmd.topic if self._cmd is not None else self.topics[command.role]
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
        self._robot.state.update(odom_stale=True)
        self._controllers.fail(error)

    def _send(self) -> None:
        if self._cmd is None:
            return
        command = self.profile.command
        self._cmd.publish(command.encode(self._types[command.role], self._command, None))
        self._sent = True

    def __repr__(self) -> str:
        state = "running" if self._cmd is not None else "stopped"
        return f"<Ros2Backend {self.node.full_name} {self.profile.name} {state}>"
