"""pyrobots_aio: an asyncio-native executive for robots.

Layers, lowest first; nothing imports upward (pinned by tests/test_layers.py):

0. ``_exceptions``
1. ``_core``: instrumentation, logging, signals, waiting (stdlib + anyio only)
2. ``loops``: the lockstep virtual-time and scaled-time loops, and their ``run``
3. ``resources``, ``state``, ``poses``
4. ``actions``, ``events``, ``telemetry`` (Foxglove channels, state sampling, the
   live view: below the robot, which owns a live view; it reads the robot
   through a protocol of its own, `telemetry.TelemetrySource`)
5. ``robot`` (the composition root)
6. ``motion`` (`DriveBase`: the motion actions, over any base's `DriveBackend`;
   the sensor table), ``supervision``
   (retry, timeout, health monitor, state machine), ``lowlevel`` (the helpers
   the layers above share: number checks, wheel-speed limits, strict JSON)
7. ``recording``, ``sim``, ``testing`` (public API only)
8. ``ros2`` (public API only)
9. ``cli`` (public API only; its ``sim-node`` runs ``sim`` over ``ros2``)

"Public API only" is pinned too: those layers import no private module of
another package (``_exceptions`` aside, for names this package exports).
"""

from ._core._events import ActionAbandonment as ActionAbandonment
from ._core._events import ActionFinished as ActionFinished
from ._core._events import ActionPaused as ActionPaused
from ._core._events import ActionResumed as ActionResumed
from ._core._events import ActionSpawned as ActionSpawned
from ._core._events import ActionStarted as ActionStarted
from ._core._events import CancelEscalated as CancelEscalated
from ._core._events import CancelRequested as CancelRequested
from ._core._events import EventKind as EventKind
from ._core._events import ExecEvent as ExecEvent
from ._core._events import LoopBlocked as LoopBlocked
from ._core._events import MonitorFired as MonitorFired
from ._core._events import ResourceAcquired as ResourceAcquired
from ._core._events import ResourceEvent as ResourceEvent
from ._core._events import ResourcePreempted as ResourcePreempted
from ._core._events import ResourceReleased as ResourceReleased
from ._core._events import ResourceSkipped as ResourceSkipped
from ._core._events import ResourceWaiting as ResourceWaiting
from ._core._events import StateSampled as StateSampled
from ._core._events import event_from_data as event_from_data
from ._core._events import event_type as event_type
from ._core._instrument import Instrument as Instrument
from ._exceptions import ActionAbandoned as ActionAbandoned
from ._exceptions import ActionCancelled as ActionCancelled
from ._exceptions import ActionDefinitionError as ActionDefinitionError
from ._exceptions import ActionError as ActionError
from ._exceptions import ActionInterrupted as ActionInterrupted
from ._exceptions import ActionSkipped as ActionSkipped
from ._exceptions import CorruptRecordingError as CorruptRecordingError
from ._exceptions import EmergencyStopError as EmergencyStopError
from ._exceptions import EventLoopError as EventLoopError
from ._exceptions import ExplorationError as ExplorationError
from ._exceptions import ExploreUnavailableError as ExploreUnavailableError
from ._exceptions import GoalError as GoalError
from ._exceptions import GoalRejectedError as GoalRejectedError
from ._exceptions import InterfaceBuildError as InterfaceBuildError
from ._exceptions import InvalidConditionError as InvalidConditionError
from ._exceptions import InvalidPoseError as InvalidPoseError
from ._exceptions import InvalidResourceError as InvalidResourceError
from ._exceptions import InvariantViolation as InvariantViolation
from ._exceptions import LockstepError as LockstepError
from ._exceptions import LockUsageError as LockUsageError
from ._exceptions import ModelLoadError as ModelLoadError
from ._exceptions import MotionError as MotionError
from ._exceptions import PoseError as PoseError
from ._exceptions import PyRobotsError as PyRobotsError
from ._exceptions import QosMismatchError as QosMismatchError
from ._exceptions import RecordingError as RecordingError
from ._exceptions import ResourceDeadlockError as ResourceDeadlockError
from ._exceptions import ResourceError as ResourceError
from ._exceptions import RobotNotRunningError as RobotNotRunningError
from ._exceptions import Ros2Error as Ros2Error
from ._exceptions import Ros2NameError as Ros2NameError
from ._exceptions import Ros2UnavailableError as Ros2UnavailableError
from ._exceptions import SimulationError as SimulationError
from ._exceptions import SimulationUnavailableError as SimulationUnavailableError
from ._exceptions import StallError as StallError
from ._exceptions import StateError as StateError
from ._exceptions import StateMachineError as StateMachineError
from ._exceptions import TooManyAbandonedCalls as TooManyAbandonedCalls
from ._exceptions import TooManyActions as TooManyActions
from ._exceptions import TopicTypeError as TopicTypeError
from ._exceptions import UnknownFrameError as UnknownFrameError
from ._exceptions import UnknownStateKeyError as UnknownStateKeyError
from .actions import Action as Action
from .actions import ActionHandle as ActionHandle
from .actions import ActionInfo as ActionInfo
from .actions import ActionState as ActionState
from .actions import BoundAction as BoundAction
from .actions import Outcome as Outcome
from .actions import action as action
from .actions import lock as lock
from .events import EventManager as EventManager
from .events import EventMonitor as EventMonitor
from .motion import DriveBackend as DriveBackend
from .motion import DriveBase as DriveBase
from .poses import FrameProvider as FrameProvider
from .poses import FrameTree as FrameTree
from .poses import Pose as Pose
from .poses import PoseLike as PoseLike
from .poses import PoseManager as PoseManager
from .resources import CompoundResource as CompoundResource
from .resources import Resource as Resource
from .resources import ResourceManager as ResourceManager
from .robot import Backend as Backend
from .robot import GenericRobot as GenericRobot
from .robot import Robot as Robot
from .state import StateSample as StateSample
from .state import StateStore as StateStore
from .supervision import HealthMonitor as HealthMonitor
from .supervision import StateMachine as StateMachine
from .supervision import exponential as exponential
from .supervision import retry as retry
from .supervision import timeout as timeout

__version__ = "0.1.0"

__all__ = [
    "Action",
    "ActionAbandoned",
    "ActionAbandonment",
    "ActionCancelled",
    "ActionDefinitionError",
    "ActionError",
    "ActionFinished",
    "ActionHandle",
    "ActionInfo",
    "ActionInterrupted",
    "ActionPaused",
    "ActionResumed",
    "ActionSkipped",
    "ActionSpawned",
    "ActionStarted",
    "ActionState",
    "Backend",
    "BoundAction",
    "CancelEscalated",
    "CancelRequested",
    "CompoundResource",
    "CorruptRecordingError",
    "DriveBackend",
    "DriveBase",
    "EmergencyStopError",
    "EventKind",
    "EventLoopError",
    "EventManager",
    "EventMonitor",
    "ExecEvent",
    "ExplorationError",
    "ExploreUnavailableError",
    "FrameProvider",
    "FrameTree",
    "GenericRobot",
    "GoalError",
    "GoalRejectedError",
    "HealthMonitor",
    "Instrument",
    "InterfaceBuildError",
    "InvalidConditionError",
    "InvalidPoseError",
    "InvalidResourceError",
    "InvariantViolation",
    "LockUsageError",
    "LockstepError",
    "LoopBlocked",
    "ModelLoadError",
    "MonitorFired",
    "MotionError",
    "Outcome",
    "Pose",
    "PoseError",
    "PoseLike",
    "PoseManager",
    "PyRobotsError",
    "QosMismatchError",
    "RecordingError",
    "Resource",
    "ResourceAcquired",
    "ResourceDeadlockError",
    "ResourceError",
    "ResourceEvent",
    "ResourceManager",
    "ResourcePreempted",
    "ResourceReleased",
    "ResourceSkipped",
    "ResourceWaiting",
    "Robot",
    "RobotNotRunningError",
    "Ros2Error",
    "Ros2NameError",
    "Ros2UnavailableError",
    "SimulationError",
    "SimulationUnavailableError",
    "StallError",
    "StateError",
    "StateMachine",
    "StateMachineError",
    "StateSample",
    "StateSampled",
    "StateStore",
    "TooManyAbandonedCalls",
    "TooManyActions",
    "TopicTypeError",
    "UnknownFrameError",
    "UnknownStateKeyError",
    "action",
    "event_from_data",
    "event_type",
    "exponential",
    "lock",
    "retry",
    "timeout",
]
