"""FakeBase: a `DriveBase` in memory, for testing behaviours without a simulator.

A round robot of the Create 3's size moves as a unicycle in a walled room with
a dock, ticking on the event loop's clock (so in virtual time, as fast as the
CPU allows). Obstacles are boxes; the robot cannot enter them (it is pushed
back out); its front bumper presses on contact, its IR rangefinders measure the
distance to the boxes, and it is ``docked`` when its charging contacts lie on
the dock's pad. No physics beyond that: commands take effect at once (up to the
simulator's top wheel speed), odometry integrates the commanded speeds exactly
in free space; against a box the wheels stall, as the simulator's do, and the
odometry follows what the robot really did (nothing, head on: a motion action
then stops with a stall). Its sensors are those of the table
(`pyrobots_aio.motion.SENSORS`): each range sensor is a ray from the robot's
rim along its bearing; a flag it does not model (a cliff: the floor has none)
reads False.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import UnknownFrameError
from ..lowlevel import as_float, finite, limit_speeds, shown
from ..motion import SENSORS, DriveBase, SensorKind, TickingBackend

if TYPE_CHECKING:
    from collections.abc import Collection, Iterable

    from numpy.typing import NDArray

    from ..motion import Pose2D, Sensor

RADIUS = 0.171
"""Metres: the robot's radius; its charging contacts are this far behind its centre."""
TRACK = 0.235
"""Metres between the wheels (the simulator's, a Create 3's)."""
TOP_WHEEL_SPEED = 0.306
"""Metres per second: the fastest a wheel turns (the simulator's, a Create 3's)."""
_HALF_TRACK = TRACK / 2
_IR_RADIUS = 0.165  # metres from the centre: where the range sensors' rays start
_CONTACT = 1e-6  # metres: closer than this to a box counts as touching it
_FLAGS = ("bumper", "bumper_left", "bumper_right", "docked")  # the flags it models
_SURE = 1 + 1e-6  # a ray is cast unless it misses a box by more than rounding could hide
_BUMPER_SIDE = 0.25  # radians: a hit this close to straight ahead presses both sides
_DOCK_PAD = (0.012, 0.04)  # half-extents of the pad the charging contacts must lie on
_DOCK_BLOCK = (0.05, 0.15)  # half-extents of the dock, behind its face


class Box:
    """A rectangular obstacle: centre ``(x, y)``, heading ``yaw``, half-extents ``hx``, ``hy``."""

    __slots__ = ("_c", "_s", "hx", "hy", "x", "y", "yaw")

    def __init__(self, x: float, y: float, yaw: float, hx: float, hy: float) -> None:
        self.x, self.y, self.yaw, self.hx, self.hy = x, y, yaw, hx, hy
        self._c, self._s = math.cos(yaw), math.sin(yaw)

    def __repr__(self) -> str:
        return f"Box(x={self.x}, y={self.y}, yaw={self.yaw}, hx={self.hx}, hy={self.hy})"

    def nearest(self, px: float, py: float) -> tuple[float, float]:
        """The point of the box nearest to ``(px, py)``, in the map."""
        c, s, hx, hy = self._c, self._s, self.hx, self.hy
        dx, dy = px - self.x, py - self.y
        if not s:  # square to the map (a wall): c is 1, the same numbers without the products
            cx = -hx if dx < -hx else hx if dx > hx else dx
            cy = -hy if dy < -hy else hy if dy > hy else dy
            return self.x + cx, self.y + cy
        lx, ly = c * dx + s * dy, -s * dx + c * dy  # in the box's frame
        cx = -hx if lx < -hx else hx if lx > hx else lx
        cy = -hy if ly < -hy else hy if ly > hy else ly
        return self.x + c * cx - s * cy, self.y + s * cx + c * cy

    def cast(self, ray: tuple[float, float, float, float, float], best: float) -> float:
        """The nearer of ``best`` and where ``ray`` meets the box.

        ``ray`` is ``(ox, oy, angle, c, s)``: from ``(ox, oy)`` at ``angle``,
        whose cosine and sine are ``c`` and ``s``. The ray is cut by the box's
        two slabs; it stops once it cannot beat ``best``.
        """
        ox, oy, angle, c, s = ray
        if self.yaw != 0.0:  # the ray's direction in the box's frame (a wall's is the map's)
            c, s = math.cos(angle - self.yaw), math.sin(angle - self.yaw)
        bc, bs = self._c, self._s
        dx, dy = ox - self.x, oy - self.y
        lx, ly = bc * dx + bs * dy, -bs * dx + bc * dy  # the origin in the box's frame
        near, far = 0.0, math.inf
        for origin, direction, half in ((lx, c, self.hx), (ly, s, self.hy)):
            if abs(direction) < 1e-12:  # parallel to the slab: in it all along, or never
                if abs(origin) > half:
                    return best
                continue
            t1, t2 = (-half - origin) / direction, (half - origin) / direction
            if t1 > t2:
                t1, t2 = t2, t1
            near, far = (t1 if t1 > near else near), (t2 if t2 < far else far)
            if near > far or near >= best:  # the next slab only narrows (near, far)
                return best
        return near


def _room(xmin: float, ymin: float, xmax: float, ymax: float) -> list[Box]:
    """The four walls (50 mm thick) around the interior ``[xmin, xmax] x [ymin, ymax]``."""
    cx, cy, hx, hy, t = (
        (xmin + xmax) / 2,
        (ymin + ymax) / 2,
        (xmax - xmin) / 2,
        (ymax - ymin) / 2,
        0.025,
    )
    return [
        Box(cx, ymax + t, 0.0, hx + 2 * t, t),
        Box(cx, ymin - t, 0.0, hx + 2 * t, t),
        Box(xmax + t, cy, 0.0, t, hy + 2 * t),
        Box(xmin - t, cy, 0.0, t, hy + 2 * t),
    ]


def _finite(name: str, values: tuple[float, ...]) -> tuple[float, ...]:
    numbers = tuple(as_float(v) for v in values)
    if None in numbers:
        msg = f"{name} must be finite numbers, got {shown(values)}"
        raise ValueError(msg)
    return cast("tuple[float, ...]", numbers)


def _bounds(name: str, box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    xmin, ymin, xmax, ymax = _finite(name, box)
    if not (xmin < xmax and ymin < ymax):
        msg = (
            f"{name} must be (xmin, ymin, xmax, ymax) with xmin < xmax and ymin < ymax, got {box!r}"
        )
        raise ValueError(msg)
    return xmin, ymin, xmax, ymax


def _planar(x: float, y: float, yaw: float) -> NDArray[np.float64]:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


class FakeWorld:
    """The fake robot's world: its true pose, odometry, command, and the boxes around it.

    Args:
        room: The interior of the walls, ``(xmin, ymin, xmax, ymax)``.
        dock: The dock's frame ``(x, y, yaw)`` in the map: on the floor at the
            middle of its face, x pointing into the room.
        obstacles: More boxes, each ``(xmin, ymin, xmax, ymax)``.
        start: Where the robot starts, ``(x, y, yaw)``; by default on the dock.
        sensors: Its sensors (default: the standard robot's, `pyrobots_aio.motion.SENSORS`).

    Attributes:
        jammed: While True, the wheels do not turn whatever the command (a
            cable caught in them): the robot and its odometry stay put. A
            test sets it to see a motion stall anywhere, turning included.

    Examples:
        >>> world = FakeWorld()
        >>> world.set_command(0.2, 0.0)
        >>> world.step(1.0)
        >>> [round(value, 3) for value in world.base_pose()]
        [-1.527, 0.0, 0.0]
    """

    def __init__(
        self,
        *,
        room: tuple[float, float, float, float] = (-2.0, -2.0, 2.0, 2.0),
        dock: Pose2D = (-1.9, 0.0, 0.0),
        obstacles: Iterable[tuple[float, float, float, float]] = (),
        start: Pose2D | None = None,
        sensors: Iterable[Sensor] = SENSORS,
    ) -> None:
        self.sensors = tuple(sensors)
        self._ray_reach = max((s.reach for s in self.sensors), default=0.0)
        # what `read_sensors` starts from: every sensor at rest, in order; then what it computes
        self._resting = {s.key: s.resting for s in self.sensors}
        self._flags = tuple(key for key in _FLAGS if key in self._resting)
        self._ranges = tuple(
            (s.key, s.bearing, s.reach) for s in self.sensors if s.kind is SensorKind.RANGE
        )
        room = _bounds("room", room)
        obstacles = [_bounds("an obstacle", box) for box in obstacles]
        dx, dy, dyaw = _finite("dock", dock)
        depth, width = _DOCK_BLOCK
        behind = (dx - depth * math.cos(dyaw), dy - depth * math.sin(dyaw))
        self.dock = dock
        self._dock_axes = (math.cos(dyaw), math.sin(dyaw))  # for `_docked`, at every tick
        self.boxes = [*_room(*room), Box(*behind, dyaw, depth, width)]
        self.boxes += [
            Box((a + c) / 2, (b + d) / 2, 0.0, (c - a) / 2, (d - b) / 2) for a, b, c, d in obstacles
        ]
        home = start or (
            dx + (RADIUS + 0.002) * math.cos(dyaw),
            dy + (RADIUS + 0.002) * math.sin(dyaw),
            dyaw,
        )
        self.command: tuple[float, float] = (0.0, 0.0)
        self.jammed = False
        self.place(*home)

    def place(self, x: float, y: float, yaw: float) -> None:
        """Put the robot at ``(x, y, yaw)`` in the map; odometry restarts there.

        Raises:
            ValueError: Not finite numbers, or the robot would overlap a box.
        """
        x, y, yaw = _finite("the pose", (x, y, yaw))
        for box in self.boxes:
            nx, ny = box.nearest(x, y)
            if math.hypot(x - nx, y - ny) < RADIUS:
                msg = (
                    f"the robot (radius {RADIUS} m) at ({x}, {y}) would overlap {box}; "
                    "place it where it is clear"
                )
                raise ValueError(msg)
        self._pose = (x, y, yaw)
        self._odom = (0.0, 0.0, 0.0)
        self._gaps: tuple[Pose2D | None, list[tuple[float, float, float]]] = (None, [])

    def set_command(self, v: float, w: float) -> None:
        """Drive at ``v`` (m/s) and ``w`` (rad/s) from the next step on.

        As on the simulator (a Create 3), no wheel goes faster than
        `TOP_WHEEL_SPEED`: a faster command is scaled down as a whole, keeping
        its curvature, and `command` holds what is applied.

        Raises:
            ValueError: ``v`` or ``w`` is not a finite number.
        """
        if not (type(v) is float and type(w) is float and math.isfinite(v) and math.isfinite(w)):
            v, w = finite("v", v), finite("w", w)  # (finite floats pass as they are)
        self.command = limit_speeds(v, w, _HALF_TRACK, TOP_WHEEL_SPEED)

    def base_pose(self) -> Pose2D:
        """The robot's true pose ``(x, y, yaw)`` in the map."""
        return self._pose

    def odom_pose(self) -> Pose2D:
        """The pose dead-reckoned from the commanded speeds, in the ``odom`` frame."""
        return self._odom

    def step(self, dt: float) -> None:
        """Move for ``dt`` seconds at the command; the boxes push the robot back out.

        The odometry moves by the command, or, when a box pushed the robot
        back, by what the robot really did (its wheels stalled with it).
        Jammed wheels (`jammed`) move nothing.
        """
        self._move(finite("dt", dt, low=0.0))

    def _move(self, dt: float) -> None:
        """`step` by ``dt``, a finite number of seconds, not negative (its backend's period)."""
        if self.jammed:
            return
        v, w = self.command
        before, turn = self._pose, w * dt
        chord = _chord(v * dt, turn)
        x, y, yaw = _arc(before, chord, turn)
        pushed = False
        gaps = []
        for box in self.boxes:
            nx, ny = box.nearest(x, y)
            gap = math.hypot(x - nx, y - ny)
            if 0.0 < gap < RADIUS:
                x, y = nx + (x - nx) * RADIUS / gap, ny + (y - ny) * RADIUS / gap
                pushed = True
            gaps.append((nx, ny, gap))
        self._pose = (x, y, yaw)
        if pushed:  # the gaps before the push are not those of the pose now
            self._odom = _carried(self._odom, before, self._pose)
        else:
            self._odom = _arc(self._odom, chord, turn)
            self._gaps = (self._pose, gaps)

    def _gaps_now(self) -> list[tuple[float, float, float]]:
        """Each box's point nearest to the robot's centre, and its distance: ``(nx, ny, gap)``.

        Those `step` found, if the robot has not moved since (it reads its sensors at every tick).
        """
        pose, gaps = self._gaps
        if pose is self._pose:
            return gaps
        x, y, _ = self._pose
        gaps = []
        for box in self.boxes:
            nx, ny = box.nearest(x, y)
            gaps.append((nx, ny, math.hypot(x - nx, y - ny)))
        return gaps

    def read_sensors(self) -> dict[str, object]:
        """Every reading, keyed as in ``robot.state``: each of `sensors`, then ``v`` and ``w``."""
        x, y, yaw = self._pose
        left = right = False
        # The boxes a range sensor's ray may reach, each with the way (mx, my) from the centre to
        # its nearest point and that distance squared (-inf: too near to tell the way).
        seen: list[tuple[Box, float, float, float]] = []
        for box, (nx, ny, gap) in zip(self.boxes, self._gaps_now(), strict=True):
            if gap <= RADIUS + _CONTACT:
                bearing = math.remainder(math.atan2(ny - y, nx - x) - yaw, math.tau)
                left |= -_BUMPER_SIDE < bearing <= math.pi / 2
                right |= -math.pi / 2 <= bearing < _BUMPER_SIDE
            if gap < _IR_RADIUS + self._ray_reach:
                seen.append((box, nx - x, ny - y, gap * gap if gap > 1e-3 else -math.inf))
        flags = {"bumper": left or right, "bumper_left": left, "bumper_right": right}
        flags["docked"] = self._docked()
        state: dict[str, object] = dict(self._resting)  # a flag it does not model reads False
        for key in self._flags:
            state[key] = flags[key]
        for key, bearing, reach in self._ranges if seen else ():  # else each reads its reach
            angle = yaw + bearing
            c, s = math.cos(angle), math.sin(angle)
            ray, best = (x + _IR_RADIUS * c, y + _IR_RADIUS * s, angle, c, s), reach
            for box, mx, my, square in seen:
                # A box lies beyond the line square to (mx, my) through its nearest point (it is
                # convex); the ray, from the centre's side along (c, s), meets that line at
                # (_IR_RADIUS + t) * ((c, s) . (mx, my)) = square: one that cannot meet it
                # within reach (with a margin for rounding) cannot meet the box, and is not cast.
                if square < (best + _IR_RADIUS) * (c * mx + s * my) * _SURE:
                    best = box.cast(ray, best)
            state[key] = best
        state["v"], state["w"] = self.command
        return state

    def frame_transform(self, frame: str) -> NDArray[np.float64]:
        """The 4x4 transform from ``frame`` (``odom``, ``base_link``, ``dock``) to ``map``."""
        if frame == "base_link":
            return _planar(*self._pose)
        if frame == "odom":  # placed so that base_link seen from odom is the odometry (REP 105)
            return _planar(*self._pose) @ np.linalg.inv(_planar(*self._odom))
        if frame == "dock":
            return _planar(*self.dock)
        msg = f"unknown frame {frame!r}; known frames: {sorted(FakeFrames.FRAMES)}"
        raise UnknownFrameError(msg)

    def _docked(self) -> bool:
        x, y, yaw = self._pose
        dx, dy, _ = self.dock
        px, py = x - RADIUS * math.cos(yaw) - dx, y - RADIUS * math.sin(yaw) - dy
        c, s = self._dock_axes
        return abs(c * px + s * py) <= _DOCK_PAD[0] and abs(-s * px + c * py) <= _DOCK_PAD[1]


def _chord(distance: float, turn: float) -> float:
    """The chord of a circular arc ``distance`` long turning by ``turn``."""
    return distance if abs(turn) < 1e-12 else 2 * distance / turn * math.sin(turn / 2)


def _arc(pose: Pose2D, chord: float, turn: float) -> Pose2D:
    """``pose`` moved along a circular arc of chord ``chord`` (`_chord`) turning by ``turn``."""
    x, y, yaw = pose
    heading = yaw + turn / 2
    return (
        x + chord * math.cos(heading),
        y + chord * math.sin(heading),
        math.remainder(yaw + turn, math.tau),
    )


def _carried(odom: Pose2D, before: Pose2D, after: Pose2D) -> Pose2D:
    """``odom`` moved as the robot moved from ``before`` to ``after`` (seen from the robot)."""
    x, y, yaw = before
    c, s = math.cos(yaw), math.sin(yaw)
    ahead, left = c * (after[0] - x) + s * (after[1] - y), -s * (after[0] - x) + c * (after[1] - y)
    ox, oy, oyaw = odom
    c, s = math.cos(oyaw), math.sin(oyaw)
    turned = math.remainder(oyaw + after[2] - yaw, math.tau)
    return ox + c * ahead - s * left, oy + s * ahead + c * left, turned


class FakeFrames:
    """The `FrameProvider` of a `FakeWorld`: ``odom``, ``base_link`` and ``dock``."""

    FRAMES = ("odom", "base_link", "dock")

    def __init__(self, world: FakeWorld) -> None:
        self._world = world

    def get_transform(self, frame: str) -> NDArray[np.float64]:
        """The 4x4 transform from ``frame`` to ``map``."""
        return self._world.frame_transform(frame)

    def frames(self) -> Collection[str]:
        """The frames a `FakeWorld` places."""
        return self.FRAMES


class FakeBackend(TickingBackend[FakeWorld]):
    """`FakeBase`'s backend: it ticks a `FakeWorld` every ``period`` seconds of the loop's clock.

    On a virtual-time loop its ticks run back to back while nothing else is
    due (`TickingBackend`); on an ordinary loop it follows the wall clock.
    """

    def __init__(self, world: FakeWorld, *, period: float) -> None:
        period = finite("period", period, positive=True, must="a positive number of seconds")
        super().__init__(world, period=period, frames=FakeFrames(world))
        self._start = 0.0

    def start_clock(self, now: float) -> float:
        """Count ticks from ``now``; the first is one period on."""
        self._start = now
        return now + self.control_period

    def advance(self) -> float:
        """Move the world by one period; the next tick is due at ``start + (ticks+1) * period``."""
        self.world._move(self.control_period)  # (the period was checked when it was set)
        return self._start + (self.ticks + 1) * self.control_period

    def __repr__(self) -> str:
        return f"<FakeBackend {1 / self.period:g} Hz tick {self.ticks}>"


class FakeBase(DriveBase):
    """A `DriveBase` in memory: the motion actions and the random walk, with no simulator.

    The robot (round, 0.171 m radius) starts on its dock in a 4 m x 4 m walled
    room (interior ``[-2, 2] x [-2, 2]``, the dock against the middle of the
    west wall), as the simulated robot does. Each control tick (``1 /
    control_rate`` of the loop's clock) it moves by the command, then
    publishes its `sensors` (the standard robot's: ``bumper``,
    ``bumper_left``, ``bumper_right``, the seven ``ir_<position>`` ranges,
    four ``cliff_<position>`` (False), ``docked``), ``v`` and ``w``, and runs
    the motion controllers (its backend is a `FakeBackend`). ``robot.world`` (a
    `FakeWorld`) holds the truth and lets a test ``place`` the robot or jam
    its wheels (``robot.world.jammed = True``). In
    virtual time (``pyrobots_aio.sim.run``, ``@pytest.mark.virtual_time``) a
    minute of driving takes milliseconds; on an ordinary loop, a minute.

    Args:
        control_rate: Control ticks per second.
        room: The interior of the walls, ``(xmin, ymin, xmax, ymax)``.
        dock: The dock's frame ``(x, y, yaw)`` in the map.
        obstacles: Boxes ``(xmin, ymin, xmax, ymax)`` in the room.
        start: The start pose ``(x, y, yaw)``; by default on the dock.
        sensors: Its sensors (default: the standard robot's, `pyrobots_aio.motion.SENSORS`).
        **options: `DriveBase` and `Robot` options (``stall_timeout``, ``max_actions`` ...).

    Examples:
        >>> from pyrobots_aio.sim import run
        >>> from pyrobots_aio.sim.random_walk import random_walk
        >>> async def main() -> tuple[int, bool]:
        ...     async with FakeBase() as robot:
        ...         report = await random_walk(robot, moves=3, seed=1)
        ...         return report.moves, robot.state.docked
        >>> run(main)
        (3, True)
    """

    def __init__(
        self,
        *,
        control_rate: float = 50.0,
        room: tuple[float, float, float, float] = (-2.0, -2.0, 2.0, 2.0),
        dock: Pose2D = (-1.9, 0.0, 0.0),
        obstacles: Iterable[tuple[float, float, float, float]] = (),
        start: Pose2D | None = None,
        sensors: Iterable[Sensor] = SENSORS,
        **options: Any,
    ) -> None:
        control_rate = finite(
            "control_rate",
            control_rate,
            positive=True,
            must="a positive number of ticks per second",
        )
        world = FakeWorld(room=room, dock=dock, obstacles=obstacles, start=start, sensors=sensors)
        fake = FakeBackend(world, period=1.0 / control_rate)
        super().__init__(backend=fake, **options)
        self.fake = fake
        self.world = world

    @property
    def ticks(self) -> int:
        """Control ticks since the robot last started."""
        return self.fake.ticks
