"""What makes ``sim-node`` a ROS 2 citizen: its options as parameters, its log on ``/rosout``.

`declare_options` serves the node's options as read-only parameters
(``ros2 param get /sim_node rate``); a ``-p`` that would set one of them is
refused, naming the option that does. `RosoutHandler` carries the
process's Python log records to the node's logger, and so to ``/rosout``
(rcl's own console output is off: the console handler prints them once).
"""

from __future__ import annotations

import importlib
import logging
from typing import TYPE_CHECKING, Any

from pyrobots_aio import PyRobotsError

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable

OPTIONS = {
    "rate": "--rate",
    "control_rate": "--control-rate",
    "cmd_timeout": "--cmd-timeout",
    "stall_timeout": "--stall-timeout",
    "seed": "--seed",
    "profile": "--profile",
}
"""sim-node's options served as parameters, by parameter name."""


def declare_options(node: Any, options: argparse.Namespace) -> None:
    """Declare each of `OPTIONS` on the rclpy ``node``, read-only, at the option's value.

    Raises:
        PyRobotsError: ``--ros-args -p`` sets one of them (the option is the way).
    """
    descriptor_type = importlib.import_module("rcl_interfaces.msg").ParameterDescriptor
    wrong_type = importlib.import_module("rclpy.exceptions").InvalidParameterTypeException
    for name, flag in OPTIONS.items():
        value = getattr(options, name)
        descriptor = descriptor_type(
            read_only=True, description=f"sim-node's {flag} option (read only)"
        )
        try:
            declared = node.declare_parameter(name, value, descriptor).value
        except wrong_type:
            declared = None
        if declared != value:
            msg = (
                f"the parameter {name!r} is sim-node's {flag} option: give {flag} VALUE "
                f"instead of -p {name}:=... in --ros-args"
            )
            raise PyRobotsError(msg)


def uses_sim_time(node: Any) -> bool:
    """Whether the rclpy ``node``'s ``use_sim_time`` parameter is true."""
    return bool(node.get_parameter("use_sim_time").value)


class RosoutHandler(logging.Handler):
    """A logging handler writing each record to an rclpy node's logger (so to ``/rosout``).

    Args:
        logger: The node's logger (``node.get_logger()``).
    """

    def __init__(self, logger: Any) -> None:
        super().__init__()
        # One calling line per severity: rclpy ties a severity to the line that logs.
        self._methods: dict[int, Callable[[str], object]] = {
            logging.DEBUG: lambda message: logger.debug(message),  # noqa: PLW0108
            logging.INFO: lambda message: logger.info(message),  # noqa: PLW0108
            logging.WARNING: lambda message: logger.warning(message),  # noqa: PLW0108
            logging.ERROR: lambda message: logger.error(message),  # noqa: PLW0108
            logging.CRITICAL: lambda message: logger.fatal(message),  # noqa: PLW0108
        }

    def emit(self, record: logging.LogRecord) -> None:
        """Log ``record``'s message at its severity (the nearest level at or below it)."""
        try:
            level = max((lv for lv in self._methods if lv <= record.levelno), default=logging.DEBUG)
            self._methods[level](self.format(record))
        except Exception:
            self.handleError(record)
