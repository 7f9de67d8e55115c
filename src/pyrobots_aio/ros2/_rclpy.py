"""What the bridge needs from rclpy, imported on first use, and checks made before any DDS work.

``import pyrobots_aio.ros2`` works without ROS 2; creating a node without
rclpy raises `Ros2UnavailableError` saying what to install. Names are checked
with rclpy's own validators, so a refusal quotes ROS 2's reason; interface
types are checked and named the ROS way (``geometry_msgs/msg/Twist``).
"""

from __future__ import annotations

import importlib
import sys
from typing import Any

from .._exceptions import Ros2NameError, Ros2UnavailableError

INSTALL = 'pip install "pyrobots-aio[ros2]"'


def rclpy_module(name: str = "rclpy") -> Any:
    """Import ``name`` (an rclpy module), or raise `Ros2UnavailableError` naming the fix."""
    try:
        return importlib.import_module(name)
    except ImportError as err:
        msg = (
            f"the ROS 2 bridge needs rclpy, which cannot be imported ({err}); install the "
            f"ROS 2 Python wheels with: {INSTALL}, or source a ROS 2 install"
        )
        raise Ros2UnavailableError(msg) from err


def _validated(kind: str, validator: str, value: object) -> str:
    if not isinstance(value, str):
        msg = f"the {kind} must be a string, got {value!r}"
        raise Ros2NameError(msg)
    module = rclpy_module(f"rclpy.{validator}")
    exceptions = rclpy_module("rclpy.exceptions")
    try:
        getattr(module, validator)(value)
    except exceptions.NameValidationException as err:
        msg = f"ROS 2 rejects the {kind} {value!r}: {err}"
        raise Ros2NameError(msg) from err
    return value


def check_node_name(name: object) -> str:
    """Return ``name`` if ROS 2 accepts it as a node name, else raise `Ros2NameError`."""
    return _validated("node name", "validate_node_name", name)


def check_namespace(namespace: object) -> str:
    """Return ``namespace`` made absolute (as rclpy does) if ROS 2 accepts it.

    ``""`` is the root namespace ``/``; ``robot1`` is ``/robot1``.
    """
    if isinstance(namespace, str) and not namespace.startswith("/"):
        namespace = "/" + namespace
    return _validated("namespace", "validate_namespace", namespace)


def check_topic(topic: object, kind: str = "topic name") -> str:
    """Return ``topic`` if ROS 2 accepts it as a topic (or service) name."""
    return _validated(kind, "validate_topic_name", topic)


def ros_name(interface: type) -> str:
    """The ROS name of a generated interface class: ``geometry_msgs/msg/Twist``.

    Examples:
        >>> class Twist: ...
        >>> Twist.__module__ = "geometry_msgs.msg._twist"
        >>> ros_name(Twist)
        'geometry_msgs/msg/Twist'
    """
    package, kind = [*interface.__module__.split("."), "", ""][:2]
    return f"{package}/{kind}/{interface.__name__}" if package and kind else interface.__name__


def check_message_type(msg_type: object) -> type:
    """Return ``msg_type`` if it is a generated ROS 2 message class, else raise TypeError."""
    if isinstance(msg_type, type) and hasattr(msg_type, "get_fields_and_field_types"):
        rclpy_module("rclpy.type_support").check_is_valid_msg_type(msg_type)
        return msg_type
    msg = (
        f"{msg_type!r} is not a ROS 2 message type; pass a generated message class, "
        "such as geometry_msgs.msg.Twist"
    )
    raise TypeError(msg)


def interface_of(value: object, part: str, kind: str) -> type:
    """The service or action class whose ``part`` (``Request``, ``Goal``) ``value`` is.

    rosidl generates ``Trigger_Request`` next to ``Trigger`` in one module, with
    ``Trigger.Request is Trigger_Request``; that is how the interface is found.

    Raises:
        TypeError: ``value`` is not such a part; the message says what to pass.
    """
    cls = type(value)
    module = sys.modules.get(cls.__module__)
    name = cls.__name__.removesuffix(f"_{part}")
    interface = getattr(module, name, None) if name != cls.__name__ else None
    if isinstance(interface, type) and getattr(interface, part, None) is cls:
        return interface
    msg = (
        f"{value!r} is not a ROS 2 {kind} {part.lower()}; pass an instance of a "
        f"generated {part} class, such as "
        + ("std_srvs.srv.Trigger.Request()" if kind == "service" else "Fibonacci.Goal(order=5)")
    )
    raise TypeError(msg)


def qos_profile(qos: object) -> Any:
    """An rclpy QoS profile from ``qos``: a history depth, a profile name, or a profile.

    Names are rclpy's presets (``"default"``, ``"sensor_data"`` — best effort,
    for sensor streams — ``"system_default"``, ``"services_default"`` ...).

    Raises:
        ValueError: An unknown profile name or a depth below 1.
        TypeError: Anything else.
    """
    qos_module = rclpy_module("rclpy.qos")
    if isinstance(qos, qos_module.QoSProfile):
        return qos
    if isinstance(qos, int) and not isinstance(qos, bool):
        if qos < 1:
            msg = f"a QoS history depth must be at least 1, got {qos!r}"
            raise ValueError(msg)
        return qos_module.QoSProfile(depth=qos)
    presets = qos_module.QoSPresetProfiles
    if isinstance(qos, str):
        known = [key for key in presets.short_keys() if key != "unknown"]
        if qos.lower() in known:
            return presets.get_from_short_key(qos)
        msg = f"unknown QoS profile {qos!r}; known profiles: {known}"
        raise ValueError(msg)
    msg = f"qos must be a history depth, a profile name or an rclpy QoSProfile, got {qos!r}"
    raise TypeError(msg)
