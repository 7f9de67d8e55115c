"""ROS 2 profiles: one table of topics, types and conversions for both ends of the wire.

A `Profile` says how a differential-drive base speaks ROS 2: its velocity
command, its odometry, the topics that carry its sensors (built from the
sensor table, `pyrobots_aio.motion.SENSORS`) and the status topics a base
publishes besides. Each `Topic` has its role (the key that remaps it), its
default name, its message type, the QoS its publisher uses, and both
conversions: ``encode`` for the end that publishes, ``decode`` for the end
that reads. `Ros2Robot` reads and commands through a profile; ``pyrobots-aio
sim-node`` publishes the simulated robot through the same one and obeys its
command, so the two cannot disagree. `STANDARD` is the standard messages'
profile; the Create 3's (``CREATE3``, in ``_create3.py``) is a second
`Profile` beside it in `PROFILES`.

Message types are named (``"sensor_msgs/msg/Range"``) and imported when a
profile is used, so this module imports without ROS 2.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, NamedTuple, TypeVar

from ..motion import SensorKind
from ._rclpy import check_message_type, rclpy_module

if TYPE_CHECKING:
    from collections.abc import Iterable

    from ..motion import Pose2D, Sensor

__all__ = ["PROFILES", "STANDARD", "Odometry", "Profile", "Topic", "profile_named"]

V = TypeVar("V")
State = Mapping[str, Any]
"""Readings by state key: what a state topic encodes from (the robot's state) and decodes to."""
Velocity = tuple[float, float]
"""A velocity command ``(v, w)``, in m/s and rad/s."""


class Odometry(NamedTuple):
    """An odometry reading: the pose in ``odom``, the measured speeds, and its stamp.

    ``stamp`` is in seconds of the publisher's clock (0.0: not stamped); encoding ignores it.
    """

    pose: Pose2D
    v: float
    w: float
    stamp: float = 0.0


@dataclass(frozen=True)
class Topic(Generic[V]):
    """One topic of a profile, with the conversions both of its ends use.

    Attributes:
        role: The name ``Ros2Robot(topics={role: ...})`` remaps it by.
        name: Its default name (relative: under the node's namespace).
        msg_type: Its message type, ``"package/msg/Type"``.
        encode: ``encode(message_class, value, stamp)``: the message the
            publishing end sends for ``value`` (``stamp`` is a
            ``builtin_interfaces/msg/Time``, for a message with a header).
        decode: ``decode(message)``: the value the reading end gets.
        qos: The QoS profile its publisher uses (``"default"``,
            ``"sensor_data"``); a `Ros2Robot` reads every input best effort,
            which matches either.
        keys: For a state topic, the state keys it carries.
    """

    role: str
    name: str
    msg_type: str
    encode: Callable[[Any, V, Any], Any] = field(repr=False)
    decode: Callable[[Any], V] = field(repr=False)
    qos: str = "default"
    keys: tuple[str, ...] = ()

    def message_class(self) -> type:
        """Import the message class (loading its type support: do it before the loop runs).

        Raises:
            Ros2UnavailableError: rclpy, or the message's package, cannot be imported.
        """
        package, kind, name = self.msg_type.split("/")
        return check_message_type(getattr(rclpy_module(f"{package}.{kind}"), name))


@dataclass(frozen=True)
class Profile:
    """How a differential-drive base speaks ROS 2: one table used by both ends.

    Attributes:
        name: Its name (``Ros2Robot(profile=name)``, ``sim-node --profile name``).
        command: The velocity command (``cmd_vel``): a base reads it, a robot sends it.
        odometry: The odometry: each message is a control tick of a `Ros2Robot`.
        sensor_topics: The topics carrying a table of sensors (`sensors` calls it).
        status: Topics a base publishes that a `Ros2Robot` does not wait for
            (a battery's state).
    """

    name: str
    command: Topic[Velocity]
    odometry: Topic[Odometry]
    sensor_topics: Callable[[tuple[Sensor, ...]], tuple[Topic[State], ...]] = field(repr=False)
    status: tuple[Topic[State], ...] = ()

    def sensors(self, sensors: Iterable[Sensor]) -> tuple[Topic[State], ...]:
        """The topics that carry ``sensors`` (a table such as `pyrobots_aio.motion.SENSORS`)."""
        return self.sensor_topics(tuple(sensors))


# -- the standard profile: geometry_msgs, nav_msgs, sensor_msgs, std_msgs -------------------


def _yaw(q: Any) -> float:
    """The yaw of a ``geometry_msgs/Quaternion``."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _float32(value: float) -> float:
    """A float32 field as the decimal it was written as (``0.4``, not ``0.4000000059604645``)."""
    return float(f"{value:.7g}")


def _encode_twist(cls: Any, velocity: Velocity, _stamp: Any) -> Any:
    twist = cls()
    twist.linear.x, twist.angular.z = velocity
    return twist


def _decode_twist(twist: Any) -> Velocity:
    return (twist.linear.x, twist.angular.z)


def _encode_odometry(cls: Any, odometry: Odometry, stamp: Any) -> Any:
    message = cls()
    message.header.stamp, message.header.frame_id, message.child_frame_id = (
        stamp,
        "odom",
        "base_link",
    )
    x, y, yaw = odometry.pose
    pose = message.pose.pose
    pose.position.x, pose.position.y = x, y
    pose.orientation.z, pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    message.twist.twist.linear.x, message.twist.twist.angular.z = odometry.v, odometry.w
    return message


def _decode_odometry(message: Any) -> Odometry:
    pose, twist, stamp = message.pose.pose, message.twist.twist, message.header.stamp
    return Odometry(
        (pose.position.x, pose.position.y, _yaw(pose.orientation)),
        twist.linear.x,
        twist.angular.z,
        stamp.sec + stamp.nanosec * 1e-9,
    )


def _flag_topic(sensor: Sensor) -> Topic[State]:
    """A ``std_msgs/Bool`` named as the sensor's key."""
    key = sensor.key
    return Topic(
        role=key,
        name=key,
        msg_type="std_msgs/msg/Bool",
        encode=lambda cls, state, _stamp: cls(data=bool(state[key])),
        decode=lambda message: {key: message.data},
        keys=(key,),
    )


def _range_topic(sensor: Sensor) -> Topic[State]:
    """A ``sensor_msgs/Range`` (infrared, one ray): ``+inf`` when nothing is in range (REP 117)."""
    key, reach = sensor.key, sensor.reach

    def encode(cls: Any, state: State, stamp: Any) -> Any:
        reading = state[key]
        ray = cls(radiation_type=cls.INFRARED, min_range=0.0, max_range=reach)
        ray.header.stamp, ray.header.frame_id = stamp, key
        ray.range = math.inf if reading >= reach else reading
        return ray

    def decode(message: Any) -> State:
        reading, limit = float(message.range), _float32(message.max_range)
        return {key: limit if not math.isfinite(reading) or reading > limit else _float32(reading)}

    return Topic(
        role=key,
        name=key,
        msg_type="sensor_msgs/msg/Range",
        encode=encode,
        decode=decode,
        qos="sensor_data",
        keys=(key,),
    )


def _one_topic_each(sensors: tuple[Sensor, ...]) -> tuple[Topic[State], ...]:
    return tuple(_range_topic(s) if s.kind is SensorKind.RANGE else _flag_topic(s) for s in sensors)


def _encode_battery(cls: Any, state: State, stamp: Any) -> Any:
    battery = cls(percentage=float(state["battery"]), present=True)
    battery.header.stamp = stamp
    battery.power_supply_status = (
        cls.POWER_SUPPLY_STATUS_CHARGING if state["docked"] else cls.POWER_SUPPLY_STATUS_DISCHARGING
    )
    return battery


STANDARD = Profile(
    name="standard",
    command=Topic(
        role="cmd_vel",
        name="cmd_vel",
        msg_type="geometry_msgs/msg/Twist",
        encode=_encode_twist,
        decode=_decode_twist,
    ),
    odometry=Topic(
        role="odom",
        name="odom",
        msg_type="nav_msgs/msg/Odometry",
        encode=_encode_odometry,
        decode=_decode_odometry,
    ),
    sensor_topics=_one_topic_each,
    status=(
        Topic(
            role="battery_state",
            name="battery_state",
            msg_type="sensor_msgs/msg/BatteryState",
            encode=_encode_battery,
            decode=lambda message: {"battery": float(message.percentage)},
            keys=("battery",),
        ),
    ),
)
"""The standard messages: ``cmd_vel`` (geometry_msgs/Twist: ``linear.x``, ``angular.z``),
``odom`` (nav_msgs/Odometry, frame ``odom``, child ``base_link``), one topic per
sensor named as its key (a range: sensor_msgs/Range, infrared, ``+inf`` when
nothing is in range, best effort; a flag: std_msgs/Bool), and ``battery_state``
(sensor_msgs/BatteryState).
"""

from ._create3 import CREATE3  # noqa: E402 - made of this module's parts, defined above

PROFILES: Mapping[str, Profile] = {STANDARD.name: STANDARD, CREATE3.name: CREATE3}
"""Every known profile, by name."""


def profile_named(profile: Profile | str) -> Profile:
    """``profile`` itself, or the known profile of that name.

    Raises:
        ValueError: No profile has that name.
    """
    if isinstance(profile, Profile):
        return profile
    known = PROFILES.get(profile)
    if known is None:
        msg = f"unknown ROS 2 profile {profile!r}; known profiles: {sorted(PROFILES)}"
        raise ValueError(msg)
    return known
