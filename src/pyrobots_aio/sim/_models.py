"""The MJCF models: where they are, and what the simulator finds in them.

The wheel ships ``models/`` as ``pyrobots_aio/models/`` (pyproject's
``force-include``); an editable install or a source checkout keeps them at the
repository root, beside ``src/``. Either way `model_path` finds them.

`ModelLayout` reads, once per loaded model, the indices and constants that
`SimWorld` needs, by the names ``models/robot.xml`` gives its parts, so that a
model lacking one fails at load time with a message naming it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import ModelLoadError
from ..motion import Sensor, SensorKind

if TYPE_CHECKING:
    from types import ModuleType

DEFAULT_SCENE = "scene.xml"
"""The model `SimWorld` loads when given none: the robot in its arena."""

_PACKAGE_DIR = Path(__file__).resolve().parent.parent
_CANDIDATES = (
    _PACKAGE_DIR / "models",  # installed from a wheel
    _PACKAGE_DIR.parent.parent / "models",  # checkout: src/pyrobots_aio -> repository root
)


def models_dir() -> Path:
    """Return the directory holding the shipped MJCF models.

    Raises:
        ModelLoadError: Neither the installed nor the checkout location holds
            the default scene (a broken install).

    Examples:
        >>> (models_dir() / "robot.xml").is_file()
        True
    """
    for candidate in _CANDIDATES:
        if (candidate / DEFAULT_SCENE).is_file():
            return candidate
    looked = ", ".join(str(c) for c in _CANDIDATES)
    raise ModelLoadError(
        f"cannot find the simulator's models ({DEFAULT_SCENE}): looked in {looked}; "
        "reinstall pyrobots-aio or pass SimWorld(model_path=...)"
    )


def model_path(name: str = DEFAULT_SCENE) -> Path:
    """Return the path of a shipped model file (the scene by default).

    Args:
        name: The file name inside ``models/``: ``"scene.xml"`` (robot and
            arena), ``"robot.xml"`` or ``"arena.xml"``.

    Raises:
        ModelLoadError: No shipped model has that name.

    Examples:
        >>> model_path().name
        'scene.xml'
    """
    directory = models_dir()
    path = directory / name
    if not path.is_file():
        known = sorted(p.name for p in directory.glob("*.xml"))
        raise ModelLoadError(f"no shipped model {name!r} in {directory}; known models: {known}")
    return path


_IR_PREFIX = "ir_"
_CLIFF_PREFIX = "cliff_"
_BUMPER_KEYS = ("bumper", "bumper_left", "bumper_right")
_MORE_KEYS = (  # read after the sensors (`ModelLayout.sensors`)
    "v",
    "w",
    "encoder_left",
    "encoder_right",
    "imu_gyro_z",
    "imu_acc_x",
    "imu_acc_y",
    "battery",
)


class _Finder:
    """Looks parts up by name; a missing part is a `ModelLoadError` naming it.

    In a world of several robots, each robot's parts (the dock's too) carry its
    ``prefix`` (``"robot2/"``; the first robot's none): names are looked up with it.
    """

    def __init__(self, mujoco: ModuleType, model: Any, path: str, prefix: str) -> None:
        self.mujoco, self.model, self.path, self.prefix = mujoco, model, path, prefix

    def id(self, kind: str, name: str) -> int:
        obj = getattr(self.mujoco.mjtObj, f"mjOBJ_{kind.upper()}")
        index = int(self.mujoco.mj_name2id(self.model, obj, self.prefix + name))
        if index < 0:
            self.fail(f"it has no {kind} named {self.prefix + name!r}")
        return index

    def sensor(self, name: str) -> int:
        return int(self.model.sensor_adr[self.id("sensor", name)])

    def numeric(self, name: str, *, positive: bool = False) -> float:
        index = self.id("numeric", name)
        value = float(self.model.numeric_data[self.model.numeric_adr[index]])
        if value < 0 or (positive and value == 0):
            self.fail(f"its numeric {name!r} must be {'> 0' if positive else '>= 0'}, not {value}")
        return value

    def rangefinders(self, prefix: str) -> list[tuple[str, int, float, float]]:
        """``(name, sensordata index, cutoff, bearing)`` of each rangefinder named ``prefix...``.

        The names are the robot's own, without its prefix in the world.
        """
        model, found = self.model, []
        rangefinder = int(self.mujoco.mjtSensor.mjSENS_RANGEFINDER)
        own = self.prefix + prefix
        for index in range(model.nsensor):
            full = str(model.sensor(index).name)
            if not full.startswith(own):
                continue
            if int(model.sensor_type[index]) != rangefinder:
                self.fail(f"its sensor {full!r} must be a rangefinder")
            name = full.removeprefix(self.prefix)
            adr, cutoff = int(model.sensor_adr[index]), float(model.sensor_cutoff[index])
            found.append((name, adr, cutoff, _bearing(model, int(model.sensor_objid[index]))))
        return found

    def fail(self, problem: str) -> None:
        raise ModelLoadError(
            f"cannot simulate the model {self.path!r}: {problem}; the simulator needs the "
            "robot of models/robot.xml and the dock of models/arena.xml (or parts so named)"
        )


@dataclass(frozen=True, slots=True)
class ModelLayout:
    """Where `SimWorld` finds the robot's parts in a loaded model, and its constants.

    Indices are into ``MjData.sensordata`` unless named otherwise; pairs are
    ``(left, right)``. Lengths in metres, speeds in rad/s, times in seconds.
    """

    wheel_radius: float
    track: float
    max_wheel_speed: float
    actuators: tuple[int, int]
    base_body: int
    free_qpos: int
    encoders: tuple[int, int]
    wheel_vels: tuple[int, int]
    gyro_z: int
    acc_xy: tuple[int, int]
    bumpers: tuple[int, int]
    ir: tuple[tuple[str, int, float], ...]
    cliffs: tuple[tuple[str, int], ...]
    dock_contact: int
    dock_pad: tuple[float, float, float]
    bumper_threshold: float
    cliff_threshold: float
    ir_noise: float
    battery_runtime: float
    battery_charge_time: float
    frame_sites: dict[str, int]
    sensors: tuple[Sensor, ...]
    state_keys: tuple[str, ...]

    @classmethod
    def from_model(cls, mujoco: ModuleType, model: Any, path: str, prefix: str = "") -> ModelLayout:
        """Read the layout of ``model`` (loaded from ``path``) of the robot named ``prefix...``.

        Raises:
            ModelLoadError: A part is missing or of the wrong kind.
        """
        find = _Finder(mujoco, model, path, prefix)
        base = find.id("body", "base_link")
        root = find.id("joint", "base_link")
        if int(model.jnt_type[root]) != int(mujoco.mjtJoint.mjJNT_FREE):
            find.fail("its joint 'base_link' must be a free joint")
        actuators = (find.id("actuator", "left_wheel"), find.id("actuator", "right_wheel"))
        wheel_y = [
            float(model.body_pos[find.id("body", n)][1]) for n in ("left_wheel", "right_wheel")
        ]
        rays = find.rangefinders(_IR_PREFIX)
        ir = tuple((name, adr, cutoff) for name, adr, cutoff, _ in rays)
        cliffs = tuple((name, adr) for name, adr, _, _ in find.rangefinders(_CLIFF_PREFIX))
        sensors = (
            *(Sensor(key, SensorKind.FLAG) for key in _BUMPER_KEYS),
            *(Sensor(k, SensorKind.RANGE, reach=cutoff, bearing=b) for k, _, cutoff, b in rays),
            *(Sensor(key, SensorKind.FLAG) for key, _ in cliffs),
            Sensor("docked", SensorKind.FLAG),
        )
        return cls(
            wheel_radius=float(model.geom_size[find.id("geom", "left_wheel")][0]),
            track=abs(wheel_y[0] - wheel_y[1]),
            max_wheel_speed=_top_speed(model, actuators),
            actuators=actuators,
            base_body=base,
            free_qpos=int(model.jnt_qposadr[root]),
            encoders=(find.sensor("encoder_left"), find.sensor("encoder_right")),
            wheel_vels=(find.sensor("wheel_vel_left"), find.sensor("wheel_vel_right")),
            gyro_z=find.sensor("imu_gyro") + 2,
            acc_xy=(find.sensor("imu_acc"), find.sensor("imu_acc") + 1),
            bumpers=(find.sensor("bumper_left"), find.sensor("bumper_right")),
            ir=ir,
            cliffs=cliffs,
            dock_contact=find.sensor("dock_contact"),
            dock_pad=_half_sizes(model, find.id("site", "dock_pad")),
            bumper_threshold=find.numeric("bumper_force_threshold"),
            cliff_threshold=find.numeric("cliff_threshold"),
            ir_noise=find.numeric("ir_noise"),
            battery_runtime=find.numeric("battery_runtime", positive=True),
            battery_charge_time=find.numeric("battery_charge_time", positive=True),
            frame_sites=_frame_sites(model, base, find.id("site", "dock"), prefix),
            sensors=sensors,
            state_keys=(*(s.key for s in sensors), *_MORE_KEYS),
        )


def _top_speed(model: Any, actuators: tuple[int, int]) -> float:
    limits = [
        float(model.actuator_ctrlrange[a][1]) if model.actuator_ctrllimited[a] else float("inf")
        for a in actuators
    ]
    return min(limits)


def _bearing(model: Any, site: int) -> float:
    """Where the site's z axis (a rangefinder's ray) points in its body's floor plane."""
    w, x, y, z = (float(v) for v in model.site_quat[site])
    return math.atan2(2 * (y * z - w * x), 2 * (x * z + w * y))


def _half_sizes(model: Any, site: int) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in model.site_size[site])
    return x, y, z


def _frame_sites(model: Any, base: int, dock: int, prefix: str) -> dict[str, int]:
    """The robot's sites (every site in the base's subtree), then the dock's; named unprefixed."""
    robot = [i for i in range(model.nsite) if int(model.body_rootid[model.site_bodyid[i]]) == base]
    return {str(model.site(i).name).removeprefix(prefix): i for i in [*robot, dock]}
