"""Test support for robot behaviours: a pytest plugin, fixtures and assertions.

Installed with the package, the ``pyrobots_aio`` pytest plugin provides the
``robot``, ``sim_robot``, ``robot_events`` and ``no_leaked_tasks`` fixtures and
the ``virtual_time`` marker; `EventLog` asserts on what the executive did.
"""

from ._events import EventLog as EventLog

__all__ = ["EventLog"]
