"""Supervision parts: what a master controller is made of, as actions and action decorators.

`retry` with an `exponential` `Backoff`, a `timeout`, a `HealthMonitor` of
heartbeats and staleness, and a `StateMachine` whose states are actions and
whose transitions are events (`When`) or outcomes. The emergency stop is the
robot's own (``robot.emergency_stop(reason)``, ``robot.clear_emergency_stop()``);
it ends every supervised plan: it cancels each running `retry`, and each
`StateMachine`'s current state, whose machine takes its failure path.

Layer: above ``robot`` (beside ``motion``); uses ``actions``, ``events``,
``state`` and ``robot``.
"""

from ._health import HealthLevel as HealthLevel
from ._health import HealthMonitor as HealthMonitor
from ._health import HealthStatus as HealthStatus
from ._machine import StateMachine as StateMachine
from ._machine import Transition as Transition
from ._machine import When as When
from ._retry import Backoff as Backoff
from ._retry import exponential as exponential
from ._retry import retry as retry
from ._timeout import TimeoutReason as TimeoutReason
from ._timeout import timed_out as timed_out
from ._timeout import timeout as timeout

__all__ = [
    "Backoff",
    "HealthLevel",
    "HealthMonitor",
    "HealthStatus",
    "StateMachine",
    "TimeoutReason",
    "Transition",
    "When",
    "exponential",
    "retry",
    "timed_out",
    "timeout",
]
