"""The Create 3 profile: iRobot's interface (``irobot_create_msgs``), both ends of the wire.

As the Create 3 documents it (iRobotEducation/create3_docs, ``api/hazards``
and ``api/ros2``), under the robot's namespace:

- ``hazard_detection`` (HazardDetectionVector, best effort): one detection
  per hazard seen now, an empty vector when none; each detection's frame
  is the sensor's. A pressed bumper is a ``BUMP`` (``bump_front_left``,
  ``bump_front_right``; a reading of ``bump_left`` or ``bump_right`` is its
  side's, ``bump_front_center`` both sides'); a cliff a ``CLIFF`` whose frame
  is the cliff sensor's key (``cliff_front_left`` ...). Other hazard types
  (``BACKUP_LIMIT``, ``STALL``, ``WHEEL_DROP`` ...) are read and ignored.
- ``ir_intensity`` (IrIntensityVector, best effort): one reading per IR
  sensor, frame ``ir_intensity_<position>``. The Create 3 reports a raw
  intensity, higher when closer, without a documented distance law; this
  profile's is linear: `IR_MAX_INTENSITY` at contact, 0 at the sensor's
  reach and beyond.
- ``dock_status`` (DockStatus): ``is_docked`` is ``docked``; the dock is
  reported visible while docked.
- ``odom`` (nav_msgs/Odometry, best effort), ``cmd_vel`` (geometry_msgs/Twist,
  reliable), ``battery_state`` (sensor_msgs/BatteryState): as `STANDARD`'s.

The action servers ``undock``, ``dock``, ``drive_distance``,
``rotate_angle`` and ``navigate_to_position`` are named in `CREATE3_ACTIONS`;
``pyrobots-aio sim-node --profile create3`` serves them, and a
``Ros2Robot(profile="create3")`` docks and undocks through them.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

from ..motion import SensorKind
from ._profiles import STANDARD, Profile, State, Topic
from ._rclpy import rclpy_module

if TYPE_CHECKING:
    from ..motion import Sensor

__all__ = ["CREATE3", "CREATE3_ACTIONS", "IR_MAX_INTENSITY"]

IR_MAX_INTENSITY = 4000
"""The Create 3 profile's IR intensity at contact (0 at the sensor's reach and beyond)."""

CREATE3_ACTIONS = {
    "undock": "irobot_create_msgs/action/Undock",
    "dock": "irobot_create_msgs/action/Dock",
    "drive_distance": "irobot_create_msgs/action/DriveDistance",
    "rotate_angle": "irobot_create_msgs/action/RotateAngle",
    "navigate_to_position": "irobot_create_msgs/action/NavigateToPosition",
}
"""The Create 3's action servers (relative names: under the robot's namespace), by name."""


def create3_action(name: str) -> Any:
    """The action type of the Create 3's action server ``name`` (a key of `CREATE3_ACTIONS`)."""
    package, kind, cls = CREATE3_ACTIONS[name].split("/")
    return getattr(rclpy_module(f"{package}.{kind}"), cls)


_BUMP_SIDES = {  # a BUMP's frame: the bumper keys it presses
    "bump_left": ("bumper_left",),
    "bump_front_left": ("bumper_left",),
    "bump_front_center": ("bumper_left", "bumper_right"),
    "bump_front_right": ("bumper_right",),
    "bump_right": ("bumper_right",),
}
_BUMP_FRAMES = {"bumper_left": "bump_front_left", "bumper_right": "bump_front_right"}


def _vector_topic(name: str, encode: Any, decode: Any, keys: tuple[str, ...]) -> Topic[State]:
    """A Create 3 sensor topic: named as its role, an ``irobot_create_msgs`` type, best effort."""
    kind = "".join(part.capitalize() for part in name.split("_"))
    return Topic(
        name,
        name,
        f"irobot_create_msgs/msg/{kind}Vector",
        encode,
        decode,
        qos="sensor_data",
        keys=keys,
    )


def _messages() -> Any:
    return rclpy_module("irobot_create_msgs.msg")


def _detection(kind: int, frame: str, stamp: Any) -> Any:
    detection = _messages().HazardDetection(type=kind)
    detection.header.stamp, detection.header.frame_id = stamp, frame
    return detection


def _hazards(sensors: tuple[Sensor, ...]) -> Topic[State]:
    cliffs = tuple(s.key for s in sensors if s.key.startswith("cliff_"))
    bumpers = tuple(s.key for s in sensors if s.key.startswith("bumper"))

    def encode(cls: Any, state: State, stamp: Any) -> Any:
        kinds = _messages().HazardDetection
        vector = cls()
        vector.header.stamp, vector.header.frame_id = stamp, "base_link"
        vector.detections = [
            *(_detection(kinds.BUMP, _BUMP_FRAMES[k], stamp) for k in _BUMP_FRAMES if state[k]),
            *(_detection(kinds.CLIFF, key, stamp) for key in cliffs if state[key]),
        ]
        return vector

    def decode(vector: Any) -> State:
        kinds = _messages().HazardDetection
        seen: dict[str, object] = dict.fromkeys((*bumpers, *cliffs), False)
        for detection in vector.detections:
            frame = detection.header.frame_id
            if detection.type == kinds.BUMP:
                seen.update(dict.fromkeys(_BUMP_SIDES.get(frame, ()), True))
            elif detection.type == kinds.CLIFF and frame in seen:
                seen[frame] = True
        if "bumper" in seen:
            seen["bumper"] = any(seen[k] for k in _BUMP_FRAMES if k in seen)
        return seen

    return _vector_topic("hazard_detection", encode, decode, (*bumpers, *cliffs))


def ir_frame(key: str) -> str:
    """The Create 3's frame of the IR sensor ``key``: ``ir_left`` is ``ir_intensity_left``."""
    return "ir_intensity_" + key.removeprefix("ir_")


def _ir(sensors: tuple[Sensor, ...]) -> Topic[State]:
    rays = {ir_frame(s.key): s for s in sensors if s.kind is SensorKind.RANGE}

    def encode(cls: Any, state: State, stamp: Any) -> Any:
        reading = _messages().IrIntensity
        vector = cls()
        vector.header.stamp, vector.header.frame_id = stamp, "base_link"
        vector.readings = []
        for frame, ray in rays.items():
            closeness = max(0.0, 1.0 - float(state[ray.key]) / ray.reach)
            one = reading(value=round(IR_MAX_INTENSITY * closeness))
            one.header.stamp, one.header.frame_id = stamp, frame
            vector.readings.append(one)
        return vector

    def decode(vector: Any) -> State:
        values, top = {r.header.frame_id: r.value for r in vector.readings}, IR_MAX_INTENSITY
        return {
            ray.key: ray.reach * (1.0 - min(values.get(frame, 0), top) / top)
            for frame, ray in rays.items()
        }

    return _vector_topic("ir_intensity", encode, decode, tuple(r.key for r in rays.values()))


def _encode_dock(cls: Any, state: State, stamp: Any) -> Any:
    status = cls(is_docked=bool(state["docked"]), dock_visible=bool(state["docked"]))
    status.header.stamp = stamp
    return status


_DOCK_STATUS: Topic[State] = Topic(
    "dock_status",
    "dock_status",
    "irobot_create_msgs/msg/DockStatus",
    _encode_dock,
    lambda status: {"docked": bool(status.is_docked)},
    keys=("docked",),
)


def _create3_topics(sensors: tuple[Sensor, ...]) -> tuple[Topic[State], ...]:
    keys = {s.key for s in sensors}
    topics = []
    if any(k.startswith(("bumper", "cliff_")) for k in keys):
        topics.append(_hazards(sensors))
    if any(s.kind is SensorKind.RANGE for s in sensors):
        topics.append(_ir(sensors))
    if "docked" in keys:
        topics.append(_DOCK_STATUS)
    return tuple(topics)


CREATE3: Profile = Profile(
    name="create3",
    command=STANDARD.command,
    odometry=dataclasses.replace(STANDARD.odometry, qos="sensor_data"),
    sensor_topics=_create3_topics,
    status=STANDARD.status,
)
"""The iRobot Create 3's interface: ``hazard_detection``, ``ir_intensity``, ``dock_status``,
``odom``, ``cmd_vel``, ``battery_state`` (see this module's top); its action servers in
`CREATE3_ACTIONS`.
"""
