"""Profiles: both ends of a topic convert through one table: what one sends, the other reads."""

from __future__ import annotations

import dataclasses
import math

import pytest
from ros2_support import require_interfaces, require_rclpy

require_rclpy()

from builtin_interfaces.msg import Time  # noqa: E402

from pyrobots_aio.motion import SENSORS  # noqa: E402
from pyrobots_aio.ros2 import (  # noqa: E402
    CREATE3,
    IR_MAX_INTENSITY,
    PROFILES,
    STANDARD,
    Odometry,
    Profile,
    Ros2Robot,
)

STAMP = Time(sec=12, nanosec=500_000_000)
STATE = {
    "bumper": True,
    "bumper_left": False,
    "bumper_right": True,
    **{s.key: 0.125 for s in SENSORS if s.key.startswith("ir_")},
    "ir_left": 0.4,  # nothing in range: +inf on the wire, the reach again on the robot
    **{s.key: False for s in SENSORS if s.key.startswith("cliff_")},
    "cliff_side_left": True,
    "docked": False,
    "battery": 0.75,
}


def test_every_standard_sensor_topic_reads_back_what_it_sent() -> None:
    topics = STANDARD.sensors(SENSORS)
    assert [t.keys for t in topics] == [(s.key,) for s in SENSORS]
    read: dict[str, object] = {}
    for topic in topics:
        message = topic.encode(topic.message_class(), STATE, STAMP)
        read.update(topic.decode(message))
    assert read == {key: value for key, value in STATE.items() if key != "battery"}
    ray = next(t for t in topics if t.role == "ir_left")
    sent = ray.encode(ray.message_class(), STATE, STAMP)
    assert (sent.range, sent.header.frame_id, sent.header.stamp) == (math.inf, "ir_left", STAMP)


def test_the_command_and_the_odometry_read_back_what_they_sent() -> None:
    command, odometry = STANDARD.command, STANDARD.odometry
    assert command.decode(command.encode(command.message_class(), (0.25, -0.5), STAMP)) == (
        0.25,
        -0.5,
    )
    sent = Odometry((1.0, -2.0, 0.5), 0.2, 0.1)
    message = odometry.encode(odometry.message_class(), sent, STAMP)
    assert (message.header.frame_id, message.child_frame_id) == ("odom", "base_link")
    read = odometry.decode(message)
    assert read.pose == pytest.approx(sent.pose)
    assert (read.v, read.w, read.stamp) == (0.2, 0.1, 12.5)


def test_the_battery_status_reads_back_what_it_sent() -> None:
    [battery] = STANDARD.status
    message = battery.encode(battery.message_class(), STATE, STAMP)
    assert message.power_supply_status == message.POWER_SUPPLY_STATUS_DISCHARGING
    assert battery.decode(message) == {"battery": 0.75}


def test_a_second_profile_sits_beside_the_standard_one_and_names_the_topics() -> None:
    assert PROFILES == {"standard": STANDARD, "create3": CREATE3}
    renamed = dataclasses.replace(
        STANDARD,
        name="renamed",
        command=dataclasses.replace(STANDARD.command, name="base/cmd_vel"),
    )
    assert isinstance(renamed, Profile)
    robot = Ros2Robot(profile=renamed, sensors=[], tf=False)
    assert robot.ros.topics == {"cmd_vel": "base/cmd_vel", "odom": "odom"}
    assert Ros2Robot(profile="standard", tf=True).ros.topics == {
        "cmd_vel": "cmd_vel",
        "odom": "odom",
        **{s.key: s.key for s in SENSORS},
        "tf": "tf",
        "tf_static": "tf_static",
    }


def create3_topics() -> dict[str, object]:
    require_interfaces("irobot_create_msgs")
    return {t.role: t for t in CREATE3.sensors(SENSORS)}


def test_the_create3_topics_read_back_what_they_sent() -> None:
    topics = create3_topics()
    assert list(topics) == ["hazard_detection", "ir_intensity", "dock_status"]
    read: dict[str, object] = {}
    for topic in CREATE3.sensors(SENSORS):
        read.update(topic.decode(topic.encode(topic.message_class(), STATE, STAMP)))
    assert read == pytest.approx({key: value for key, value in STATE.items() if key != "battery"})
    assert (CREATE3.odometry.qos, CREATE3.command.qos) == ("sensor_data", "default")


def test_create3_hazards_are_bumps_with_the_bumpers_frame_and_cliffs_with_the_cliffs() -> None:
    hazards = CREATE3.sensors(SENSORS)[0]
    vector = hazards.encode(hazards.message_class(), STATE, STAMP)
    assert [(d.type, d.header.frame_id) for d in vector.detections] == [
        (1, "bump_front_right"),  # HazardDetection.BUMP
        (2, "cliff_side_left"),  # HazardDetection.CLIFF
    ]
    assert vector.detections[0].header.stamp == STAMP
    center = type(vector.detections[0])(type=1)
    center.header.frame_id = "bump_front_center"
    stall = type(vector.detections[0])(type=3)  # STALL: not a sensor of the table
    stall.header.frame_id = "left_wheel"
    read = hazards.decode(hazards.message_class()(detections=[center, stall]))
    assert {k: v for k, v in read.items() if v} == {
        "bumper": True,
        "bumper_left": True,
        "bumper_right": True,
    }
    assert not any(hazards.decode(hazards.message_class()()).values())


def test_create3_ir_intensities_are_higher_when_closer_named_by_the_create3_frames() -> None:
    ir = CREATE3.sensors(SENSORS)[1]
    state = {**STATE, "ir_front_left": 0.0, "ir_right": 0.3}
    vector = ir.encode(ir.message_class(), state, STAMP)
    values = {r.header.frame_id: r.value for r in vector.readings}
    assert values == {
        "ir_intensity_side_left": 2750,
        "ir_intensity_left": 0,
        "ir_intensity_front_left": IR_MAX_INTENSITY,
        "ir_intensity_front_center_left": 2750,
        "ir_intensity_front_center_right": 2750,
        "ir_intensity_front_right": 2750,
        "ir_intensity_right": 1000,
    }
