"""Event monitors: callbacks on conditions over the robot's state (pyRobots/URBI ``whenever``).

Layer: beside ``actions``; uses ``_core``, ``state``, ``actions`` and ``_exceptions``.
"""

from ._conditions import Conditions as Conditions
from ._manager import EventManager as EventManager
from ._manager import Predicate as Predicate
from ._monitor import EventMonitor as EventMonitor

__all__ = ["Conditions", "EventManager", "EventMonitor", "Predicate"]
