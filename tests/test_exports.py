"""The public namespaces, pinned (httpx's test_exported_members): each one's exact ``__all__``.

Adding or removing a public name is a deliberate change: it edits ``EXPORTS``
here, in review. Every exported name is importable, has no leading underscore,
and is documented: a class, function or module by its own docstring, anything
else (a constant, a type alias, a context variable) by the docstring under its
assignment, where Sphinx and editors read it.
"""

from __future__ import annotations

import ast
import asyncio
import importlib
import importlib.util
import inspect
import itertools
from functools import cache
from pathlib import Path
from types import ModuleType

import pytest

import pyrobots_aio

EXPORTS: dict[str, list[str]] = {
    "pyrobots_aio": [
        "Action", "ActionAbandoned", "ActionAbandonment", "ActionCancelled",
        "ActionDefinitionError", "ActionError", "ActionFinished", "ActionHandle",
        "ActionInfo", "ActionInterrupted", "ActionPaused", "ActionResumed", "ActionSkipped",
        "ActionSpawned", "ActionStarted", "ActionState", "Backend", "BoundAction",
        "CancelEscalated", "CancelRequested", "CompoundResource", "CorruptRecordingError",
        "DriveBackend", "DriveBase", "EmergencyStopError", "EventKind", "EventLoopError",
        "EventManager", "EventMonitor", "ExecEvent", "ExplorationError",
        "ExploreUnavailableError", "FrameProvider", "FrameTree", "GenericRobot",
        "GoalError", "GoalRejectedError", "HealthMonitor", "Instrument",
        "InterfaceBuildError", "InvalidConditionError", "InvalidPoseError",
        "InvalidResourceError", "InvariantViolation", "LockUsageError", "LockstepError",
        "LoopBlocked", "ModelLoadError", "MonitorFired", "MotionError", "Outcome", "Pose",
        "PoseError", "PoseLike", "PoseManager", "PyRobotsError", "QosMismatchError",
        "RecordingError",
        "Resource", "ResourceAcquired", "ResourceDeadlockError", "ResourceError",
        "ResourceEvent", "ResourceManager", "ResourcePreempted", "ResourceReleased",
        "ResourceSkipped", "ResourceWaiting", "Robot", "RobotNotRunningError", "Ros2Error",
        "Ros2NameError", "Ros2UnavailableError", "SimulationError",
        "SimulationUnavailableError", "StallError", "StateError", "StateMachine",
        "StateMachineError", "StateSample", "StateSampled", "StateStore",
        "TooManyAbandonedCalls", "TooManyActions", "TopicTypeError", "UnknownFrameError",
        "UnknownStateKeyError", "action", "event_from_data", "event_type", "exponential",
        "lock", "retry", "timeout",
    ],
    "pyrobots_aio.actions": [
        "Action", "ActionHandle", "ActionInfo", "ActionState", "BoundAction", "Outcome",
        "action", "current_action", "lock",
    ],
    "pyrobots_aio.cli": [
        "ConsoleHandler", "SignalStop", "install_console_handler", "main", "stop_on_signals",
    ],
    "pyrobots_aio.events": ["Conditions", "EventManager", "EventMonitor", "Predicate"],
    "pyrobots_aio.lowlevel": [
        "as_float", "finite", "jsonable", "limit_speeds", "null_nonfinite", "park", "shown",
        "strict_json", "wrap_angle",
    ],
    "pyrobots_aio.loops": [
        "ScaledTimeLoop", "VirtualTimeLoop", "is_virtual", "new_virtual_loop", "run_lockstep",
        "run_scaled", "scaled_loop",
    ],
    "pyrobots_aio.motion": [
        "ANGLE_TOLERANCE", "DISTANCE_TOLERANCE", "SENSORS", "STALL_TIMEOUT", "WHEELS",
        "Controllers", "DriveBackend", "DriveBase", "Pose2D", "Sensor", "SensorKind",
        "TickedWorld", "TickingBackend",
    ],
    "pyrobots_aio.poses": [
        "FrameProvider", "FrameTree", "Matrix", "Pose", "Pose2D", "PoseLike", "PoseManager",
    ],
    "pyrobots_aio.recording": [
        "FORMAT", "VERSION", "ActionStats", "Cancellation", "Failure", "JsonlRecorder",
        "JsonlSink", "McapRecorder", "McapSink", "MemoryRecorder", "MemorySink", "Outcomes",
        "PoseTrack", "Recorder", "Recording", "RecordingHeader", "RecordingOptions",
        "ResourceStats", "Series", "Sink", "Summary", "format_summary", "load",
        "render_timeline_html", "shown", "summarize",
    ],
    "pyrobots_aio.resources": [
        "AnyResource", "CompoundResource", "Grant", "Owner", "Resource", "ResourceManager",
    ],
    "pyrobots_aio.robot": ["Backend", "GenericRobot", "Robot", "SignalStop", "stop_on_signals"],
    "pyrobots_aio.ros2": [
        "CREATE3", "CREATE3_ACTIONS", "DOCK_IN_ODOM", "IR_MAX_INTENSITY", "PROFILES",
        "STANDARD", "InterfaceBuild", "InterfaceOutcome", "Odometry", "Profile",
        "Ros2ActionServer", "Ros2Backend", "Ros2Node", "Ros2Publisher", "Ros2Robot",
        "Ros2ServiceServer", "Ros2Subscription", "TfBroadcaster", "TfBuffer", "ToState",
        "Topic", "attach_ros2", "build_interfaces", "interface_packages", "profile_named",
        "serve_create3", "tf_available",
    ],
    "pyrobots_aio.sim": [
        "WHEELS", "SimBackend", "SimRobot", "SimWorld", "WorldFrames", "model_path",
        "models_dir", "run",
    ],
    "pyrobots_aio.sim.random_walk": [
        "BACK_OFF", "DETOUR", "DOCK_ATTEMPTS", "LEAVE_DOCK", "REFLEX_PRIORITY", "WalkReport",
        "bumper_reflex", "move", "random_walk", "suspending_reflex",
    ],
    "pyrobots_aio.state": ["StateSample", "StateStore", "Subscription"],
    "pyrobots_aio.supervision": [
        "Backoff", "HealthLevel", "HealthMonitor", "HealthStatus", "StateMachine",
        "TimeoutReason", "Transition", "When", "exponential", "retry", "timed_out", "timeout",
    ],
    "pyrobots_aio.telemetry": [
        "ARENA", "EVENT", "FIXED_CHANNELS", "POSE_IN_FRAME", "SAMPLE", "SCENE_UPDATE", "SCHEMAS",
        "FloorShape", "FoxgloveChannels", "LiveView", "LogForwarder", "Message",
        "StateSampler", "TelemetrySource", "floor_plan",
    ],
    "pyrobots_aio.testing": [
        "EventLog", "FakeBase", "FakeWorld", "Injection", "inject_bump", "inject_state",
    ],
    "pyrobots_aio.testing.explore": [
        "PROFILES", "SAFETY", "At", "Bump", "Cancel", "Cliff", "Disturbance", "EmergencyStop",
        "Hit", "Invariant", "On", "Pause", "Preempt", "Reading", "Run", "Scenario", "Silence",
        "StaleOdometry", "Target", "completes", "ends_docked", "no_action_outlives_robot",
        "no_forward_into_bumper", "no_resource_held_twice", "still_while_stopped",
    ],
}  # fmt: skip
PACKAGE = Path(pyrobots_aio.__file__).parent
PUBLIC_NAMES = [(module, name) for module, names in EXPORTS.items() for name in names]


def _public_modules() -> list[str]:
    """Every module of the package whose dotted path has no ``_`` part (``__main__`` aside)."""
    found = []
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if not any(part.startswith("_") for part in parts):
            found.append(".".join(parts))
    return sorted(found)


def test_every_public_module_is_pinned() -> None:
    assert _public_modules() == sorted(EXPORTS)


@pytest.mark.parametrize("module", EXPORTS)
def test_all_is_exactly_the_pinned_list(module: str) -> None:
    assert importlib.import_module(module).__all__ == EXPORTS[module]


@pytest.mark.parametrize("module", EXPORTS)
def test_a_star_import_brings_exactly_the_public_names(module: str) -> None:
    namespace: dict[str, object] = {}
    exec(f"from {module} import *", namespace)  # the import is the test
    assert sorted(set(namespace) - {"__builtins__"}) == sorted(EXPORTS[module])


@pytest.mark.parametrize("module", EXPORTS)
def test_nothing_private_is_exported(module: str) -> None:
    assert [name for name in EXPORTS[module] if name.startswith("_")] == []


PACKAGES = [module for module in EXPORTS if hasattr(importlib.import_module(module), "__path__")]


@pytest.mark.parametrize("module", PACKAGES)
def test_a_package_holds_no_public_name_outside_all(module: str) -> None:
    """A package's namespace is its re-exports: one outside ``__all__`` slipped past review."""
    mod = importlib.import_module(module)
    extra = {
        name
        for name, value in vars(mod).items()
        if not name.startswith("_")
        and name not in mod.__all__
        and not isinstance(value, ModuleType)  # submodules (pyrobots_aio.sim.random_walk)
        and name not in {"annotations", "TYPE_CHECKING"}
    }
    assert extra == set(), f"{module} has public names outside __all__: {sorted(extra)}"


def _source_of(module: str) -> Path:
    spec = importlib.util.find_spec(module)
    assert spec is not None
    assert spec.origin is not None
    return Path(spec.origin)


@cache
def _tree(module: str) -> ast.Module:
    return ast.parse(_source_of(module).read_text())


def _imported_from(module: str, name: str) -> str | None:
    """The module ``module`` takes ``name`` from, resolved; None if it defines ``name``."""
    package = module if _source_of(module).name == "__init__.py" else module.rpartition(".")[0]
    for node in _tree(module).body:
        if isinstance(node, ast.ImportFrom) and any(
            (alias.asname or alias.name) == name for alias in node.names
        ):
            base = package.split(".")[: len(package.split(".")) - node.level + 1]
            return ".".join([*base, node.module] if node.level else [node.module or ""])
    return None


def _targets(node: ast.stmt) -> set[str]:
    if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
        return {node.target.id}
    if isinstance(node, ast.Assign):
        names = [t.elts if isinstance(t, ast.Tuple) else [t] for t in node.targets]
        return {n.id for group in names for n in group if isinstance(n, ast.Name)}
    return set()


def _attribute_docstring(module: str, name: str) -> str | None:
    """The string right under the assignment of ``name``, in the module that makes it."""
    while (source := _imported_from(module, name)) is not None:
        module = source
    body = _tree(module).body
    for node, after in itertools.pairwise(body):
        if name in _targets(node) and isinstance(after, ast.Expr):
            value = after.value
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                return value.value
    return None


def _own_docstring(obj: object) -> str | None:
    """The docstring ``obj`` carries itself: not its class's, its alias's origin's, nor the
    one dataclass generates."""
    doc = obj.__doc__
    if inspect.isclass(obj):
        return None if doc is None or doc.startswith(f"{obj.__name__}(") else doc
    if inspect.isfunction(obj) or inspect.isbuiltin(obj) or isinstance(obj, ModuleType):
        return doc
    borrowed = (type(obj).__doc__, getattr(getattr(obj, "__origin__", None), "__doc__", None))
    return None if doc in borrowed else doc  # an action keeps its own


@pytest.mark.parametrize(("module", "name"), PUBLIC_NAMES, ids=[".".join(p) for p in PUBLIC_NAMES])
def test_every_public_name_is_documented(module: str, name: str) -> None:
    obj = getattr(importlib.import_module(module), name)
    doc = _own_docstring(obj) or _attribute_docstring(module, name)
    assert (doc or "").strip(), f"{module}.{name} has no docstring"


def test_the_check_finds_an_attribute_docstring_through_re_exports() -> None:
    # pyrobots_aio takes PoseLike from .poses, which takes it from ._parse
    assert _attribute_docstring("pyrobots_aio", "PoseLike") == (
        "Anything `PoseManager.get` reads as a pose."
    )
    assert _attribute_docstring("pyrobots_aio.sim", "WHEELS") == (
        "The drive wheels: every motion action holds them."
    )
    assert _own_docstring(pyrobots_aio.Resource("x")) is None  # its class's docstring: not its own
    assert _own_docstring(tuple[float, float]) is None  # nor an alias's, its origin's
    assert _attribute_docstring("pyrobots_aio.ros2._profiles", "V") is None  # a bare TypeVar


def test_the_design_names_are_importable_from_the_package() -> None:
    names = {
        "Robot", "GenericRobot", "action", "ActionHandle", "Outcome", "ActionCancelled",
        "ActionInterrupted", "ActionSkipped", "TooManyActions", "PyRobotsError", "Resource",
        "CompoundResource", "lock", "Pose", "FrameProvider", "InvalidPoseError",
        "UnknownFrameError", "EventMonitor", "StateStore", "ActionInfo", "DriveBase",
        "retry", "exponential", "timeout", "HealthMonitor", "StateMachine",
        "ResourceDeadlockError",
    }  # fmt: skip
    assert names <= set(pyrobots_aio.__all__)
    assert pyrobots_aio.ActionCancelled is asyncio.CancelledError
