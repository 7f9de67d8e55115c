"""The simulated world: MuJoCo physics, sensors, odometry and frames of the robot.

`SimWorld` is the only object in pyrobots_aio that touches MuJoCo's ``MjModel``
and ``MjData``. It knows nothing of asyncio: the simulated robot calls
`SimWorld.step` (or `SimWorld.advance`) from its control loop and publishes
`SimWorld.read_sensors` to ``robot.state``. (The module is over 400 lines
because it keeps every touch of ``MjData`` in one class; the odometry's
arithmetic lives in ``_odometry``.)

Time is an integer count of physics steps (``data.time`` accumulates rounding
error); `SimWorld.time` is ``steps * physics_dt`` from a start that
`SimWorld.set_time` moves (a running simulated robot sets it to the event
loop's clock). After each call to ``step`` the sensors, poses and frames
describe the state at `SimWorld.time`.

Determinism: MuJoCo is deterministic, and the only randomness is the IR noise
(standard deviation ``ir_noise`` in the model, added only to readings that see
something), drawn from a generator seeded with ``seed``. The same seed and the
same calls give bit-identical trajectories and readings. How the steps are
batched (``step(10)`` or ten ``step(1)``) does not change the physics, nor
does how `step` saves work (a test pins it to plain ``mj_step`` bit for bit); the
odometry, like a robot's firmware, integrates the encoders once per call (as a
circular arc), so it differs by micrometres.

Several robots: ``SimWorld(robots=N)`` holds N copies of the robot in one
physics (``_scene``: each on its own dock, 0.5 m apart), so they see and
bump into one another. The world is then N `SimWorld` objects, one per
robot (`SimWorld.robots`; the one constructed is the first): each has the
robot's own API (commands, sensors, odometry, frames, IR noise from its own
generator) and all share the physics, its step count and its clock, so
stepping any of them steps them all.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .. import SimulationUnavailableError, UnknownFrameError
from ..lowlevel import finite, limit_speeds
from ._models import ModelLayout
from ._models import model_path as _default_model_path
from ._odometry import Odometry
from ._scene import MAX_ROBOTS, load_model, robot_prefix

if TYPE_CHECKING:
    from types import ModuleType

    from numpy.typing import NDArray

    from ..motion import Sensor

__all__ = ["SimWorld"]

_log = logging.getLogger("pyrobots_aio.sim")

_HOME_KEYFRAME = "home"
_NOISE_BLOCK = 256  # sensor readings whose IR noise is drawn at once


def _import_mujoco() -> ModuleType:
    try:
        import mujoco
    except ImportError as err:
        _raise_interrupt(err)
        raise SimulationUnavailableError(
            f"the simulated robot needs MuJoCo, which cannot be imported ({err}); "
            'install it with: pip install -e ".[sim]" in a pyrobots_aio checkout'
        ) from err
    module: ModuleType = mujoco
    _route_warnings(module)
    return module


def _raise_interrupt(error: ImportError) -> None:
    """Raise the `KeyboardInterrupt` behind ``error``, if any: Ctrl-C is no missing package.

    MuJoCo's extension modules (pybind11) turn whatever interrupts their
    initialisation into ``ImportError: initialization failed``, the interrupt
    as its cause (Ctrl-C while ``SimRobot()`` is being built).
    """
    seen: set[int] = set()
    cause: BaseException | None = error
    while cause is not None and id(cause) not in seen:
        if not isinstance(cause, Exception):  # KeyboardInterrupt, SystemExit
            raise cause from None
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__


def _route_warnings(mujoco: ModuleType) -> None:
    """Send MuJoCo's warnings to the ``pyrobots_aio.sim`` logger, once per process.

    MuJoCo's own handler prints them and appends them to ``MUJOCO_LOG.TXT`` in
    the current directory. Its handler is process-wide: one a program set
    itself is left in place.
    """
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_mujoco_warning)


def _mujoco_warning(message: str) -> None:
    _log.warning("MuJoCo: %s", message)


def _yaw(qw: float, qx: float, qy: float, qz: float) -> float:
    return math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))


def _planar(x: float, y: float, yaw: float) -> NDArray[np.float64]:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])


def _matrix(pos: NDArray[np.float64], rot: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.empty((4, 4))  # filled at once (the pose of the base is sampled every tick)
    out[:3, :3] = rot.reshape(3, 3)
    out[:3, 3] = pos
    out[3] = _LAST_ROW
    return out


class _Shared:
    """What the robots of one world share: the physics, its step count and clock, the robots."""

    __slots__ = (
        "clock_start",
        "data",
        "dt",
        "model",
        "mujoco",
        "path",
        "robots",
        "running",
        "seed",
        "steps",
    )

    def __init__(self, mujoco: ModuleType, model: Any, path: Path, seed: int, dt: float) -> None:
        self.mujoco, self.model, self.data = mujoco, model, mujoco.MjData(model)
        self.path, self.seed, self.dt = path, seed, dt
        self.steps = 0
        self.clock_start = (0.0, 0)  # `time` reads this time at this step
        self.robots: tuple[SimWorld, ...] = ()
        self.running: set[int] = set()  # the robots whose simulated robot runs (`enter_run`)


class SimWorld:
    """The MuJoCo simulation of the differential-drive robot in its arena.

    Args:
        model_path: An MJCF file; by default the shipped ``models/scene.xml``.
            Another model must contain the robot of ``models/robot.xml`` (the
            simulator finds its parts by name) and a dock (``arena.xml``).
        seed: Seeds the IR noise; the same seed and calls give the same run.
        physics_dt: The physics step in seconds (overrides the model's).
        robots: How many robots share the world (1 to 7): copies of the
            model's robot, each on its own copy of the dock, 0.5 m apart along
            y (0, +0.5, -0.5 ...). This object is the first; `robots` has all.

    Raises:
        SimulationUnavailableError: MuJoCo is not installed.
        ModelLoadError: The model does not load, or lacks a part the simulator
            needs; the message names the file and the problem.
        ValueError: ``physics_dt`` is not a positive number, or ``robots`` out of range.

    Examples:
        >>> world = SimWorld(seed=1)
        >>> world.set_command(0.2, 0.0)
        >>> world.advance(1.0)
        500
        >>> round(world.odom_pose()[0], 1)
        0.2
        >>> first, second = SimWorld(robots=2).robots
        >>> second.set_command(0.2, 0.0)
        >>> first.advance(1.0)  # one physics: the second robot moves too
        500
        >>> round(second.odom_pose()[0], 1), round(second.base_pose()[1], 1)
        (0.2, 0.5)
    """

    MAX_ROBOTS: ClassVar[int] = MAX_ROBOTS
    """The most robots a world holds (``robots=``): seven docks fit along the arena's wall."""

    def __init__(
        self,
        model_path: str | Path | None = None,
        *,
        seed: int = 0,
        physics_dt: float = 0.002,
        robots: int = 1,
    ) -> None:
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, not {seed!r}")
        physics_dt = finite(
            "physics_dt", physics_dt, positive=True, must="a positive number of seconds"
        )
        if isinstance(robots, bool) or not isinstance(robots, int) or not 0 < robots <= MAX_ROBOTS:
            raise ValueError(
                f"robots must be a whole number from 1 to {MAX_ROBOTS} (one dock each), "
                f"not {robots!r}"
            )
        mujoco = _import_mujoco()
        path = Path(model_path) if model_path is not None else _default_model_path()
        model = load_model(mujoco, path, robots)
        model.opt.timestep = physics_dt
        shared = _Shared(mujoco, model, path, seed, physics_dt)
        shared.robots = (self, *(SimWorld.__new__(SimWorld) for _ in range(robots - 1)))
        for index, world in enumerate(shared.robots):
            world._join(shared, index)
        self._reset_to_home()
        _log.debug(
            "loaded %s: %d robot(s), %d IR and %d cliff sensors each, seed %d",
            path,
            robots,
            len(self._layout.ir),
            len(self._layout.cliffs),
            seed,
        )

    def _join(self, shared: _Shared, index: int) -> None:
        """Set this robot's side of the world up: robot ``index`` of ``shared``'s physics."""
        mujoco, model, data, path = shared.mujoco, shared.model, shared.data, shared.path
        self._opt = model.opt  # a view of the model's options, fetched once (each fetch costs)
        self._sensors_off = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        # mj_step2 integrates as mj_step does, except RK4 (it falls back to Euler).
        self._split_step = model.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4
        self._layout = ModelLayout.from_model(mujoco, model, str(path), robot_prefix(index))
        self._site_indices = np.fromiter(self._layout.frame_sites.values(), dtype=np.intp)
        self._mujoco, self._model, self._data = mujoco, model, data
        self._sensordata, self._ctrl = data.sensordata, data.ctrl  # views, fetched once
        body = self._layout.base_body  # the base's position and the first row of its rotation
        self._base_xpos, self._base_xmat = data.xpos[body], data.xmat[body, :4]
        self._dofs = np.flatnonzero(model.body_rootid[model.dof_bodyid] == body)
        self._path, self._seed, self._dt = path, shared.seed, shared.dt
        self._shared, self._index = shared, index
        self._readings: list[float] = []  # sensordata of the current state, as floats
        self._is_docked = False  # of the current state
        # The first robot's noise is drawn as a world of one robot draws it.
        self._rng = np.random.default_rng([shared.seed, index] if index else shared.seed)
        self._noise: list[float] = []  # IR noise drawn ahead, consumed in order
        self._noise_used = 0
        self._command = (0.0, 0.0)
        self._battery = 1.0

    def __repr__(self) -> str:
        robots = len(self._shared.robots)
        which = f" robot {self._index + 1} of {robots}" if robots > 1 else ""
        return f"<SimWorld {self._path.name}{which} seed={self._seed} t={self.time:.3f}s>"

    @property
    def robots(self) -> tuple[SimWorld, ...]:
        """Every robot of the world, the first first: one `SimWorld` each, sharing the physics.

        ``SimWorld(robots=2).robots`` is ``(the world, its second robot)``; a
        world of one robot is ``(itself,)``. Give one to ``SimRobot(world=...)``.
        """
        return self._shared.robots

    @property
    def model_path(self) -> Path:
        """The MJCF file the world was loaded from."""
        return self._path

    @property
    def seed(self) -> int:
        """The seed of the IR noise."""
        return self._seed

    @property
    def physics_dt(self) -> float:
        """The physics step, in seconds."""
        return self._dt

    @property
    def steps(self) -> int:
        """The number of physics steps taken since construction."""
        return self._shared.steps

    @property
    def time(self) -> float:
        """The simulation clock, in seconds: ``steps * physics_dt`` unless `set_time` moved it."""
        return self.time_after(0)

    def time_after(self, steps: int) -> float:
        """Return what `time` will read after ``steps`` more physics steps.

        Computed from whole steps, so it equals `time` exactly once they are taken.
        """
        return self.time_at(self._shared.steps + steps)

    def time_at(self, step: int) -> float:
        """Return what `time` reads once `steps` reads ``step`` (unless `set_time` moves it)."""
        start, at_step = self._shared.clock_start
        return start + (step - at_step) * self._dt

    def set_time(self, now: float) -> None:
        """Make `time` read ``now`` at the current step; it advances by `physics_dt` per step.

        The physics does not change: only the clock's start moves (`steps` still
        counts from construction).

        Raises:
            ValueError: ``now`` is not a finite number.
        """
        now = finite("the simulation time", now)
        self._shared.clock_start = (now, self._shared.steps)

    def enter_run(self, now: float) -> None:
        """Count this robot as running; the first to run sets the clock to ``now``.

        A simulated robot calls it as it starts, `leave_run` as it stops: the
        first robot of a world to start sets the clock (as `set_time`), the
        others join the clock running (the physics is one).

        Raises:
            ValueError: ``now`` is not a finite number.
        """
        shared = self._shared
        if not shared.running:
            self.set_time(now)
        shared.running.add(self._index)

    def leave_run(self) -> None:
        """No longer count this robot as running (see `enter_run`)."""
        self._shared.running.discard(self._index)

    @property
    def command(self) -> tuple[float, float]:
        """The velocity command in force, ``(v, w)``, after speed limiting."""
        return self._command

    @property
    def state_keys(self) -> tuple[str, ...]:
        """The keys of `read_sensors`, in the order it returns them."""
        return self._layout.state_keys

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The robot's sensors as its model has them (the shipped one: `motion.SENSORS`).

        The bumper's, IR rangefinders', cliff sensors' and the dock's: the
        first keys of `read_sensors`, each with its kind, and for a
        rangefinder its cutoff and the direction it looks.
        """
        return self._layout.sensors

    @property
    def frame_names(self) -> tuple[str, ...]:
        """The frames of `frame_transforms`, in the order it returns them."""
        return ("odom", "base_link", *self._layout.frame_sites)

    # --- commands and time ----------------------------------------------------------

    def set_command(self, v: float, w: float) -> None:
        """Drive at linear speed ``v`` (m/s) and angular speed ``w`` (rad/s).

        The wheel speeds follow from the wheel radius and track. A command that
        needs a wheel faster than its top speed is scaled down as a whole, so the
        robot keeps the commanded curvature; `command` reports the result.

        Any finite numbers are taken (``1.7e308`` gives the top speed).

        Raises:
            ValueError: ``v`` or ``w`` is not a finite number.
        """
        if not (type(v) is float and type(w) is float and math.isfinite(v) and math.isfinite(w)):
            v, w = finite("v", v), finite("w", w)  # (finite floats pass as they are)
        layout = self._layout
        half_track, radius = layout.track / 2, layout.wheel_radius
        v, w = limit_speeds(v, w, half_track, layout.max_wheel_speed * radius)
        self._ctrl[layout.actuators[0]] = (v - w * half_track) / radius
        self._ctrl[layout.actuators[1]] = (v + w * half_track) / radius
        self._command = (v, w)

    def stop(self) -> None:
        """Command zero speed: the wheel servos brake the robot to a halt."""
        self.set_command(0.0, 0.0)

    def step(self, n: int = 1) -> None:
        """Advance the physics by ``n`` steps of `physics_dt`.

        Raises:
            ValueError: ``n`` is negative.
        """
        if n < 0:
            raise ValueError(f"cannot step a negative number of physics steps ({n})")
        if n == 0:
            return
        mujoco, model, data, opt = self._mujoco, self._model, self._data, self._opt
        # Sensors are read only after the last step: skip them in the steps (they never
        # feed back into the physics), then compute everything once for the new state.
        flags = opt.disableflags
        opt.disableflags = flags | self._sensors_off
        try:
            rest = n
            if self._split_step:
                # The last `_forward` left positions and velocities computed; only the
                # command may have changed since: mj_step2 does the rest of a step.
                mujoco.mj_step2(model, data)
                rest -= 1
            if rest:
                mujoco.mj_step(model, data, rest)  # (nstep by position: a keyword costs more)
        finally:
            opt.disableflags = flags
        self._forward()
        self._shared.steps += n
        elapsed = n * self._dt
        for robot in self._shared.robots:
            readings, (left, right) = robot._readings, robot._layout.encoders
            robot._odometry.update(readings[left], readings[right])
            robot._update_battery(elapsed)

    def advance(self, dt: float) -> int:
        """Advance the physics by ``dt`` seconds and return the steps taken.

        Raises:
            ValueError: ``dt`` is negative or not a whole number of physics steps.
        """
        n = round(finite("dt", dt) / self._dt)
        if n < 0 or not math.isclose(n * self._dt, dt, rel_tol=1e-9, abs_tol=1e-12):
            raise ValueError(
                f"dt={dt!r} s is not a whole, non-negative number of physics steps "
                f"of {self._dt} s; use a multiple of physics_dt"
            )
        self.step(n)
        return n

    def place(self, x: float, y: float, yaw: float) -> None:
        """Put the robot down at rest at ``(x, y, yaw)`` in the map frame.

        For setting up scenarios and tests: the robot is put down as it rests
        at the start (same height and tilt), with no speed. Odometry restarts
        there (the ``odom`` frame moves to the new pose); the command, time and
        battery are kept.

        Raises:
            ValueError: A coordinate is not a finite number.
        """
        x, y, yaw = finite("x", x), finite("y", y), finite("yaw", yaw)
        layout, data, mujoco = self._layout, self._data, self._mujoco
        qpos = layout.free_qpos
        data.qpos[qpos : qpos + 3] = (x, y, self._rest_z)
        heading = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
        mujoco.mju_mulQuat(data.qpos[qpos + 3 : qpos + 7], heading, self._rest_tilt)
        data.qvel[self._dofs] = 0.0  # this robot's: the others keep moving
        self._forward()
        self._odometry.reset(*self._encoders())

    # --- sensors ---------------------------------------------------------------------

    def read_sensors(self) -> dict[str, object]:
        """Return every sensor reading, keyed as in ``robot.state``.

        Keys (see `state_keys`): ``bumper``, ``bumper_left``, ``bumper_right``
        (bool); ``ir_<position>`` (float, m: the sensor's range when nothing is
        in range); ``cliff_<position>`` (bool: True over a cliff); ``docked``
        (bool); ``v`` (m/s) and ``w`` (rad/s), measured at the wheels;
        ``encoder_left``, ``encoder_right`` (rad); ``imu_gyro_z`` (rad/s);
        ``imu_acc_x``, ``imu_acc_y`` (m/s^2, body frame); ``battery`` (0 to 1).
        """
        layout, s = self._layout, self._readings
        threshold = layout.bumper_threshold
        left = s[layout.bumpers[0]] > threshold
        right = s[layout.bumpers[1]] > threshold
        state: dict[str, object] = {"bumper": left or right, "bumper_left": left}
        state["bumper_right"] = right
        # The IR noise: one value per IR sensor, drawn `_NOISE_BLOCK` readings at a time (one
        # call instead of one per reading): NumPy draws a block as the same sequence of values
        # that as many small draws would give, so the readings are unchanged.
        count, start = len(layout.ir), self._noise_used
        if start >= len(self._noise):
            self._noise = self._rng.normal(0.0, layout.ir_noise, count * _NOISE_BLOCK).tolist()
            start = 0
        self._noise_used = start + count
        noise = self._noise[start : start + count]
        for (key, index, limit), error in zip(layout.ir, noise, strict=True):
            distance = s[index]
            if 0.0 <= distance < limit:  # sees something: noisy, clamped to [0, limit]
                # min(max(d, 0.0), limit) to the bit (-0.0 and NaN too), without the calls.
                distance += error
                distance = 0.0 if distance < 0.0 else distance
                state[key] = limit if limit < distance else distance
            else:
                state[key] = limit
        cliff = layout.cliff_threshold
        for key, index in layout.cliffs:
            distance = s[index]
            state[key] = distance < 0.0 or distance > cliff
        state["docked"] = self._is_docked
        wheel_left, wheel_right = s[layout.wheel_vels[0]], s[layout.wheel_vels[1]]
        state["v"] = layout.wheel_radius * (wheel_left + wheel_right) / 2
        state["w"] = layout.wheel_radius * (wheel_right - wheel_left) / layout.track
        state["encoder_left"] = s[layout.encoders[0]]
        state["encoder_right"] = s[layout.encoders[1]]
        state["imu_gyro_z"] = s[layout.gyro_z]
        state["imu_acc_x"] = s[layout.acc_xy[0]]
        state["imu_acc_y"] = s[layout.acc_xy[1]]
        state["battery"] = self._battery
        return state

    # --- poses and frames ------------------------------------------------------------

    def base_pose(self) -> tuple[float, float, float]:
        """Return the robot's true pose ``(x, y, yaw)`` in the map frame (m, rad)."""
        body = self._layout.base_body
        x, y, _ = self._data.xpos[body].tolist()
        return x, y, _yaw(*self._data.xquat[body].tolist())

    def odom_pose(self) -> tuple[float, float, float]:
        """Return the pose ``(x, y, yaw)`` dead-reckoned from the wheel encoders.

        It is in the ``odom`` frame, which starts at the robot's start pose (or
        its last `place`); wheel slip makes it drift from `base_pose`.
        """
        odometry = self._odometry
        return odometry.x, odometry.y, odometry.yaw

    def frame_transforms(self) -> dict[str, NDArray[np.float64]]:
        """Return every frame as a 4x4 homogeneous transform to the map frame.

        Frames: ``odom`` (placed, as ROS REP 105 has it, so that ``base_link``
        seen from ``odom`` is the dead-reckoned `odom_pose`), ``base_link`` (the
        true pose, on the floor under the wheel axle), one frame per sensor
        site of the robot (``ir_<position>``, ``cliff_<position>``,
        ``bumper_left``, ``bumper_right``, ``imu``, ``charge_contacts``) and
        ``dock`` (on the floor at the dock's face, x into the room).
        """
        sites = self._layout.frame_sites
        indices = self._site_indices
        stacked = np.zeros((len(indices), 4, 4))
        stacked[:, :3, :3] = self._data.site_xmat[indices].reshape(-1, 3, 3)
        stacked[:, :3, 3] = self._data.site_xpos[indices]
        stacked[:, 3, 3] = 1.0
        frames = {"odom": self._odom_in_map(), "base_link": self._base_in_map()}
        frames.update(zip(sites, stacked, strict=True))
        return frames

    def frame_transform(self, frame: str) -> NDArray[np.float64]:
        """Return one frame of `frame_transforms` as a 4x4 transform to the map frame.

        Raises:
            UnknownFrameError: The world has no such frame.
        """
        if frame == "odom":
            return self._odom_in_map()
        if frame == "base_link":
            return self._base_in_map()
        index = self._layout.frame_sites.get(frame)
        if index is None:
            raise UnknownFrameError(
                f"unknown frame {frame!r}; known frames: {sorted(self.frame_names)}"
            )
        return _matrix(self._data.site_xpos[index], self._data.site_xmat[index])

    def frame_planar(self, frame: str) -> tuple[float, float, float]:
        """Return ``(x, y, yaw)`` of one frame in the map: `frame_transform`'s floor-plane part.

        The same numbers, read from the physics without building the matrix.

        Raises:
            UnknownFrameError: The world has no such frame.
        """
        if frame == "base_link":  # (the recorders' frame, at every tick)
            x, y, _ = self._base_xpos.tolist()
            r0, _, _, r1 = self._base_xmat.tolist()
            return (x, y, math.atan2(r1, r0))
        index = self._layout.frame_sites.get(frame)
        if index is None:  # odom (composed), or unknown: the matrix's way
            (r0, _, _, x), (r1, _, _, y) = self.frame_transform(frame)[:2].tolist()
            return (x, y, math.atan2(r1, r0))
        x, y, _ = self._data.site_xpos[index].tolist()
        r0, _, _, r1 = self._data.site_xmat[index, :4].tolist()
        return (x, y, math.atan2(r1, r0))

    def floor_plan(self) -> list[dict[str, Any]]:
        """Return the static shapes the robot can run into, seen from above, in the map frame.

        Each solid geom fixed to the world (walls, obstacles, the dock; not the
        floor, nor the robot) as a JSON-friendly dict: ``name``, ``kind`` (its
        material's name, else its own: ``wall``, ``obstacle``, ``dock`` in the
        shipped arena), ``x``, ``y`` and ``yaw`` of its centre, ``rgba``, and
        ``shape``: ``"box"`` with ``half`` ``[hx, hy]``, or ``"circle"`` with
        ``radius`` (cylinders; other shapes by their bounding radius), and
        ``z`` and ``height``, its centre's height and its own (Foxglove's 3D
        view stands the shapes up). Replay draws its map from this.

        Examples:
            >>> world = SimWorld()
            >>> [s["name"] for s in world.floor_plan() if s["kind"] == "dock"]
            ['dock']
        """
        mujoco, model, data = self._mujoco, self._model, self._data
        shapes = []
        for geom in range(model.ngeom):
            static = model.body_weldid[model.geom_bodyid[geom]] == 0
            solid = model.geom_contype[geom] or model.geom_conaffinity[geom]
            if not static or not solid or model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_PLANE:
                continue
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, geom) or f"geom{geom}"
            material = model.geom_matid[geom]
            kind = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_MATERIAL, material) or name
            rgba = model.mat_rgba[material] if material >= 0 else model.geom_rgba[geom]
            x, y, z = data.geom_xpos[geom].tolist()
            rot = data.geom_xmat[geom]
            shape: dict[str, Any] = {"name": name, "kind": kind, "x": x, "y": y}
            shape.update(
                yaw=math.atan2(float(rot[3]), float(rot[0])),
                rgba=[round(float(c), 3) for c in rgba],
            )
            size = model.geom_size[geom]
            if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_BOX:
                shape.update(shape="box", half=[float(size[0]), float(size[1])])
                half_height = float(size[2])
            elif model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
                shape.update(shape="circle", radius=float(size[0]))
                half_height = float(size[1])
            else:
                half_height = float(model.geom_rbound[geom])
                shape.update(shape="circle", radius=half_height)
            shape.update(z=z, height=2 * half_height)
            shapes.append(shape)
        return shapes

    # --- internals -------------------------------------------------------------------

    def _reset_to_home(self) -> None:
        mujoco, model, data = self._mujoco, self._model, self._data
        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, _HOME_KEYFRAME)
        if key >= 0:
            mujoco.mj_resetDataKeyframe(model, data, key)
        self._forward()
        for robot in self._shared.robots:
            robot._settle()

    def _settle(self) -> None:
        """Note how the robot rests; start its odometry where it stands."""
        mujoco, data = self._mujoco, self._data
        left, right = self._encoders()
        self._odometry = Odometry(self._layout.wheel_radius, self._layout.track, left, right)
        # How the robot rests on the floor (its height, and its tilt onto the
        # caster with the heading taken out), so that `place` puts it down settled.
        qpos = self._layout.free_qpos
        self._rest_z = float(data.qpos[qpos + 2])
        yaw = _yaw(*data.qpos[qpos + 3 : qpos + 7].tolist())
        unturn = np.array([math.cos(yaw / 2), 0.0, 0.0, -math.sin(yaw / 2)])
        self._rest_tilt = np.empty(4)
        mujoco.mju_mulQuat(self._rest_tilt, unturn, data.qpos[qpos + 3 : qpos + 7])

    def _forward(self) -> None:
        """Compute positions, forces and every sensor for the current state; cache the readings.

        First the checks `mj_step` makes before its own forward pass (a diverged
        state is reset), since `step` reuses this pass for its first step.
        """
        mujoco, model, data = self._mujoco, self._model, self._data
        mujoco.mj_checkPos(model, data)
        mujoco.mj_checkVel(model, data)
        mujoco.mj_forward(model, data)
        s = self._sensordata.tolist()
        for robot in self._shared.robots:
            robot._readings = s
            start = robot._layout.dock_contact
            px, py, pz = s[start : start + 3]
            hx, hy, hz = robot._layout.dock_pad
            robot._is_docked = abs(px) <= hx and abs(py) <= hy and abs(pz) <= hz

    def _encoders(self) -> tuple[float, float]:
        left, right = self._layout.encoders
        return self._readings[left], self._readings[right]

    def _update_battery(self, elapsed: float) -> None:
        layout = self._layout
        if self._is_docked:
            self._battery = min(1.0, self._battery + elapsed / layout.battery_charge_time)
        else:
            self._battery = max(0.0, self._battery - elapsed / layout.battery_runtime)

    def _base_in_map(self) -> NDArray[np.float64]:
        body = self._layout.base_body
        return _matrix(self._data.xpos[body], self._data.xmat[body])

    def _odom_in_map(self) -> NDArray[np.float64]:
        # map->odom = map->base (truth) composed with the inverse of odom->base
        # (dead reckoning), both in the floor plane: rotate by the yaw difference,
        # then put the dead-reckoned position onto the true one.
        x, y, yaw = self.base_pose()
        odometry = self._odometry
        turn = yaw - odometry.yaw
        c, s = math.cos(turn), math.sin(turn)
        return _planar(
            x - c * odometry.x + s * odometry.y, y - s * odometry.x - c * odometry.y, turn
        )
