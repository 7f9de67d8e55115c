"""The robot: the composition root of actions, resources, state, events and poses."""

from .._core._signals import SignalStop as SignalStop
from .._core._signals import stop_on_signals as stop_on_signals
from ._backend import Backend as Backend
from ._robot import GenericRobot as GenericRobot
from ._robot import Robot as Robot

__all__ = ["Backend", "GenericRobot", "Robot", "SignalStop", "stop_on_signals"]
