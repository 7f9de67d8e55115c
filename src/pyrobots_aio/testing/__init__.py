"""Test support for robot behaviours: a pytest plugin, fixtures and assertions.

Installed with the package, the ``pyrobots_aio`` pytest plugin provides the
``robot``, ``sim_robot``, ``robot_events`` and ``no_leaked_tasks`` fixtures and
the ``virtual_time`` marker; `EventLog` asserts on what the executive did;
`FakeBase` is a `pyrobots_aio.DriveBase` in memory (no simulator) for
testing motion behaviours in virtual time; `inject_bump` and `inject_state`
press the bumper (or write any state) at a chosen action boundary.
`pyrobots_aio.testing.explore` (the ``explore`` extra: Hypothesis) searches
for the schedule of disturbances that breaks a behaviour, and the plugin's
``explore`` fixture runs it.
"""

from ._events import EventLog as EventLog
from ._fakebase import FakeBase as FakeBase
from ._fakebase import FakeWorld as FakeWorld
from ._inject import Injection as Injection
from ._inject import inject_bump as inject_bump
from ._inject import inject_state as inject_state

__all__ = ["EventLog", "FakeBase", "FakeWorld", "Injection", "inject_bump", "inject_state"]
