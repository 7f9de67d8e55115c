"""The robot: the composition root of actions, resources, state, events and poses."""

from ._backend import Backend as Backend
from ._robot import GenericRobot as GenericRobot
from ._robot import Robot as Robot

__all__ = ["Backend", "GenericRobot", "Robot"]
