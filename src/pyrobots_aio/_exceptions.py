"""The one exception hierarchy of pyrobots_aio.

Every error the library raises on purpose is a `PyRobotsError`; messages name
the bad value and say how to fix it.

```
PyRobotsError
├── RobotNotRunningError          an action or monitor used with no running robot
├── EventLoopError                used from another thread, event loop or async library
├── TooManyAbandonedCalls         robot.to_thread refused: abandoned calls fill its threads
├── ActionError
│   ├── ActionInterrupted         awaited action was cancelled (.reason, .by, .handle)
│   ├── ActionSkipped             action did not run: a resource was busy
│   ├── TooManyActions            Robot(max_actions=N) reached (.running)
│   └── ActionDefinitionError     @action applied to something that is not an async def
├── ResourceError
│   ├── InvalidResourceError      not a resource, or a compound that contains itself
│   ├── LockUsageError            lock() misused (outside an action, re-entered, ...)
│   └── ResourceDeadlockError     a request would close a lock cycle (.cycle)
├── StateError
│   ├── UnknownStateKeyError      also a KeyError and an AttributeError
│   └── InvalidConditionError     a monitor with no, two, or a mistyped condition
├── PoseError
│   ├── InvalidPoseError          also a ValueError
│   └── UnknownFrameError         also a KeyError
├── SimulationError
│   ├── SimulationUnavailableError  mujoco is not installed
│   ├── ModelLoadError            an MJCF file that does not load
│   └── LockstepError             a lockstep robot outside the lockstep loop
├── MotionError                   a motion action that cannot do its job (docking failed)
│   ├── EmergencyStopError        motion refused: the emergency stop is latched (.reason)
│   └── StallError                a motion commanded the wheels and went nowhere (.action, ...)
├── StateMachineError             a StateMachine refused when built (unknown state, bad trigger)
├── RecordingError
│   └── CorruptRecordingError     a recording line that cannot be read (.line)
├── ExplorationError              pyrobots_aio.testing.explore
│   ├── ExploreUnavailableError   Hypothesis is not installed (also an ImportError)
│   └── InvariantViolation        a run broke its invariants (also an AssertionError; .schedule)
└── Ros2Error
    ├── Ros2UnavailableError      rclpy is not installed (also an ImportError)
    ├── Ros2NameError             a name ROS 2 rejects, with its reason (also a ValueError)
    ├── TopicTypeError            a topic that carries another type (also a TypeError)
    ├── QosMismatchError          a topic's two ends whose QoS cannot match (both named)
    ├── GoalError                 a ROS 2 goal that did not succeed (.status)
    │   └── GoalRejectedError     the action server refused the goal
    └── InterfaceBuildError       interface packages that cannot be built (what is missing)
```

`ActionCancelled` is not in this tree: it *is* `asyncio.CancelledError`
(an alias), the exception that arrives inside a cancelled action. Nor is
`ActionAbandoned`, a ``BaseException`` thrown into the body of an action that
ignored cancellation for two graces, to end it.
"""

from __future__ import annotations

import asyncio
from collections import Counter
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Sequence

ActionCancelled = asyncio.CancelledError
"""Raised inside a cancelled action at its next ``await``; it *is* ``asyncio.CancelledError``."""


class ActionAbandoned(BaseException):
    """Thrown into the body of an action that ignored cancellation for two graces, to end it.

    A ``BaseException``, as ``GeneratorExit`` is: ``except Exception`` and
    ``except ActionCancelled`` let it through, so a body that swallows every
    cancellation still ends, its ``finally`` blocks running. The action's
    outcome is already CANCELLED; do not catch this.
    """


class PyRobotsError(Exception):
    """Root of every error raised on purpose by pyrobots_aio."""


class RobotNotRunningError(PyRobotsError):
    """An action or monitor was used while its robot is not running."""


class EventLoopError(PyRobotsError, RuntimeError):
    """The robot was used from a thread, event loop or async library it does not run on.

    A robot belongs to the asyncio event loop that runs ``async with robot``;
    the message names the way in from elsewhere (``robot.call_soon_threadsafe``,
    ``robot.run_threadsafe``, ``anyio.from_thread.run``).
    """


class TooManyAbandonedCalls(PyRobotsError, RuntimeError):
    """``robot.to_thread`` refused a call: too many abandoned calls still run in its threads.

    A call is abandoned when its caller is cancelled: Python cannot stop a
    thread, so the call runs on until it returns.

    Attributes:
        running: The names of the abandoned calls' functions, one per call.
    """

    def __init__(self, name: str, running: Sequence[str]) -> None:
        self.running = list(running)
        counts = Counter(self.running).items()  # in the order of the first of each
        shown = ", ".join(f"{each} ({n})" if n > 1 else each for each, n in counts)
        super().__init__(
            f"cannot call robot.to_thread({name}): {len(self.running)} abandoned calls still "
            f"run in its threads ({shown}), the most it keeps; their callers were cancelled, but "
            "Python cannot stop a thread: give the blocking calls a timeout so that they return"
        )


class ActionError(PyRobotsError):
    """Errors about actions."""


class ActionInterrupted(ActionError):
    """Raised when awaiting an action that was cancelled.

    Attributes:
        reason: The reason given to `ActionHandle.cancel`, or None.
        by: The handle of the action that cancelled it, or None when the
            cancellation came from outside any action.
        handle: The handle of the interrupted action.
    """

    def __init__(self, handle: Any, reason: str | None, by: Any) -> None:
        self.handle = handle
        self.reason = reason
        self.by = by
        who = f" by {by.name}#{by.id}" if by is not None else ""
        why = f": {reason}" if reason else ""
        super().__init__(f"action {handle.name}#{handle.id} was cancelled{who}{why}")


class ActionSkipped(ActionError):
    """Raised when awaiting an action that did not run because a resource was busy.

    The message names the resource and what stands in the way: its holder, or
    the earlier queued request it is promised to (a ``wait=False`` request never
    overtakes one), or both when a ``preempt=True, wait=False`` request could
    cancel the holder but would then still wait behind a queued request.

    Attributes:
        resource: The busy resource.
        holder: The handle of the action holding it, or None when it is free
            but promised to ``queued``.
        queued: The handle of the earlier queued request it is promised to, or
            None when only ``holder`` is in the way.
        queued_priority: The priority of that queued request (None without one).
        handle: The handle of the skipped action (None until attached).
    """

    def __init__(
        self,
        resource: Any,
        holder: Any,
        handle: Any = None,
        *,
        queued: Any = None,
        queued_priority: int | None = None,
    ) -> None:
        self.resource = resource
        self.holder = holder
        self.queued = queued
        self.queued_priority = queued_priority
        self.handle = handle
        held = f"is busy (held by {holder.name}#{holder.id})" if holder is not None else "is busy"
        if queued is None:
            what = held
        else:
            promised = (
                f"promised to {queued.name}#{queued.id} (queued ahead, priority {queued_priority})"
            )
            what = f"{held} and {promised}" if holder is not None else f"is {promised}"
        super().__init__(f"skipped: resource {resource.name!r} {what}")


class TooManyActions(ActionError):
    """Raised when starting an action would exceed ``Robot(max_actions=N)``.

    Attributes:
        running: The handles of the actions running at that moment.
    """

    def __init__(self, name: str, limit: int, running: Sequence[Any]) -> None:
        self.running = list(running)
        shown = ", ".join(f"{h.name}#{h.id}" for h in self.running[:10])
        more = f" and {len(self.running) - 10} more" if len(self.running) > 10 else ""
        super().__init__(
            f"cannot start {name!r}: {len(self.running)} actions already running "
            f"(max_actions={limit}): {shown}{more}; raise max_actions or cancel some"
        )


class ActionDefinitionError(ActionError, TypeError):
    """``@action`` was applied to something it cannot turn into an action."""


class ResourceError(PyRobotsError):
    """Errors about resources and locks."""


class InvalidResourceError(ResourceError, TypeError):
    """Something that is not a valid resource was given where one is needed."""


class LockUsageError(ResourceError):
    """``lock()`` was misused."""


class ResourceDeadlockError(ResourceError):
    """A request for a resource would close a cycle of actions waiting for each other.

    Nested locks taken in opposite orders (``async with lock(A)`` then
    ``lock(B)`` in one action, ``B`` then ``A`` in another) would wait for
    ever: the request that closes the cycle raises this instead of waiting,
    in the action that made it; the others then go on once it lets go of
    what it holds. Take the resources in one order everywhere, or together as
    one `CompoundResource` (taken atomically, it cannot deadlock).

    Attributes:
        cycle: The steps of the cycle, ``(waiter, resource name, holder)``,
            starting with the action that raised: each waiter waits for the
            resource its holder holds, and the last holder is that action
            (or an ancestor holding until it is done).
    """

    def __init__(self, cycle: Sequence[tuple[Any, str, Any]]) -> None:
        self.cycle = tuple(cycle)
        steps = "; ".join(
            f"{w.name}#{w.id} waits for {r!r} held by {h.name}#{h.id}" for w, r, h in cycle
        )
        super().__init__(
            f"lock cycle (deadlock): {steps}; take the resources in one order everywhere, "
            "or together as one CompoundResource"
        )


class StateError(PyRobotsError):
    """Errors about the state store and monitors."""


class UnknownStateKeyError(StateError, KeyError, AttributeError):
    """A state key that does not exist; the message lists the closest keys."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class InvalidConditionError(StateError, ValueError):
    """A monitor condition that is missing, duplicated or of the wrong type."""


class PoseError(PyRobotsError):
    """Errors about poses and frames."""


class InvalidPoseError(PoseError, ValueError):
    """A value that cannot be read as a pose; the message says what was expected."""


class UnknownFrameError(PoseError, KeyError):
    """A frame no provider knows; the message lists the known frames."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class SimulationError(PyRobotsError):
    """Errors of the simulated robot."""


class SimulationUnavailableError(SimulationError, ImportError):
    """MuJoCo is not installed; install the ``sim`` extra."""


class ModelLoadError(SimulationError):
    """An MJCF model that does not load."""


class LockstepError(SimulationError):
    """A lockstep simulated robot was used outside the lockstep event loop."""


class MotionError(PyRobotsError):
    """A motion action of a `DriveBase` could not do its job (docking failed)."""


class EmergencyStopError(MotionError):
    """Motion refused: the robot's emergency stop is latched.

    Raised by ``drive`` and the motion actions of a `DriveBase` from
    ``robot.emergency_stop(reason)`` until ``robot.clear_emergency_stop()``,
    and by a `StateMachine` that a stop ended in a state with no FAILED
    transition. `retry` never retries it.

    Attributes:
        reason: The reason the emergency stop was given.
    """

    def __init__(self, what: str, reason: str) -> None:
        self.reason = reason
        super().__init__(
            f"{what} refused: the emergency stop is latched ({reason!r}); call "
            "robot.clear_emergency_stop() once it is safe to move"
        )


class StallError(MotionError):
    """A motion action commanded motion and its odometry showed no progress: the robot is blocked.

    Raised by the motion actions of a `DriveBase` once no progress lasted the
    base's ``stall_timeout`` (by default `pyrobots_aio.motion.STALL_TIMEOUT`); the
    wheels are stopped.

    Attributes:
        action: The motion action's name (``"drive_distance"``).
        command: The wheel command ``(v, w)`` (m/s, rad/s) that went nowhere.
        seconds: How long it went without progress.
        timeout: The base's ``stall_timeout`` then.
    """

    def __init__(
        self, action: str, command: tuple[float, float], seconds: float, timeout: float
    ) -> None:
        self.action, self.command, self.seconds, self.timeout = action, command, seconds, timeout
        v, w = command
        super().__init__(
            f"{action} stalled: the wheels were commanded v={v + 0.0:.3g} m/s, "
            f"w={w + 0.0:.3g} rad/s, and the odometry showed no progress for {seconds:.2f} s "
            f"(something blocks the robot; the bound is robot.stall_timeout = {timeout:g} s)"
        )


class StateMachineError(PyRobotsError, ValueError):
    """A `StateMachine` refused when it is built: an unknown state, a bad trigger or condition."""


class RecordingError(PyRobotsError):
    """Errors reading or writing recordings."""


class CorruptRecordingError(RecordingError):
    """A recording line that cannot be read.

    Attributes:
        path: The recording file.
        line: The 1-based line number of the bad line.
    """

    def __init__(self, path: str, line: int, problem: str) -> None:
        self.path = path
        self.line = line
        super().__init__(f"{path}:{line}: {problem}")


class ExplorationError(PyRobotsError):
    """Errors of scenario exploration (`pyrobots_aio.testing.explore`)."""


class ExploreUnavailableError(ExplorationError, ImportError):
    """Hypothesis cannot be imported; install the ``explore`` extra."""


class InvariantViolation(ExplorationError, AssertionError):
    """A run broke its invariants: the schedule that did it, as code, and what broke.

    Attributes:
        schedule: The hits (shrunk, when found by exploring).
        violations: What broke, in words.
        recording: The run's recording (JSON Lines), when one was made.
    """

    def __init__(
        self,
        message: str,
        schedule: Sequence[object],
        violations: Sequence[str],
        recording: str | None = None,
    ) -> None:
        self.schedule = tuple(schedule)
        self.violations = tuple(violations)
        self.recording = recording
        super().__init__(message)


class Ros2Error(PyRobotsError):
    """Errors of the ROS 2 bridge (`pyrobots_aio.ros2`)."""


class Ros2UnavailableError(Ros2Error, ImportError):
    """rclpy cannot be imported; install the ``ros2`` extra or source a ROS 2 install."""


class Ros2NameError(Ros2Error, ValueError):
    """A node name, namespace, topic or service name that ROS 2 rejects (its reason quoted)."""


class TopicTypeError(Ros2Error, TypeError):
    """A topic used with a message type other than the one it carries; both are named."""


class QosMismatchError(Ros2Error):
    """A publisher and a subscription of one topic whose QoS profiles cannot match; both named.

    DDS never delivers between them (a best-effort publisher, a reliable
    subscription): without this error, the subscription would just stay silent.
    """


class GoalError(Ros2Error):
    """A ROS 2 action goal that did not succeed.

    Attributes:
        action: The action's name (e.g. ``/fibonacci``).
        status: How it ended: ``"rejected"``, ``"aborted"`` or ``"canceled"``.
    """

    def __init__(self, action: str, status: str, message: str) -> None:
        self.action = action
        self.status = status
        super().__init__(message)


class GoalRejectedError(GoalError):
    """The action server refused the goal."""


class InterfaceBuildError(Ros2Error):
    """Interface packages that cannot be built: the tools missing, each with its fix, or the log."""
