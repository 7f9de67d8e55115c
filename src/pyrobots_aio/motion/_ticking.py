"""The simulated bases' control loop: tick a world in step with the event loop, publish it.

One `TickingBackend` serves the simulator (``SimBackend``) and the in-memory
fake (``FakeBackend``). Each tick is a plain loop callback (no task),
scheduled with ``call_at`` at the time the world's clock reads after the
tick (computed from whole steps, so lockstep time stays exact and equal to
the world's). A tick advances the world by one control period, writes every
reading to ``robot.state`` in one batch (monitors see each tick's values),
then runs the controllers the motion actions registered. In lockstep the
loop's virtual clock jumps from tick to tick; in real time the same code
runs against the wall clock.

In lockstep, when nothing else would run before the next tick (no callback
ready, no earlier timer), the next tick runs at once in the same callback:
the loop's turn in between would only have polled I/O. The ticks, and
everything they compute, are the same; the loop still turns every
`TICKS_PER_TURN` ticks.
"""

from __future__ import annotations

import abc
import asyncio
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar, cast

from .._exceptions import PyRobotsError, RobotNotRunningError
from ..loops import VirtualTimeLoop, is_virtual
from ._control import Controllers

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..poses import FrameProvider, Pose2D
    from ..robot import Robot
    from ._sensors import Sensor

TICKS_PER_TURN = 10
"""Lockstep ticks run back to back at most (when nothing else is due between them)."""


class TickedWorld(Protocol):
    """The simulated world a `TickingBackend` ticks (``SimWorld``, ``FakeWorld``)."""

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The sensors `read_sensors` reads (besides ``v``, ``w`` and extras)."""

    def set_command(self, v: float, w: float) -> None:
        """Drive at ``v`` (m/s) and ``w`` (rad/s) until the next command."""

    def odom_pose(self) -> Pose2D:
        """The pose dead-reckoned from the wheels, in the ``odom`` frame."""

    def base_pose(self) -> Pose2D:
        """The true pose, in the ``map`` frame."""

    def read_sensors(self) -> dict[str, object]:
        """Every reading now, keyed as in ``robot.state`` (a fresh dict, given up)."""


W = TypeVar("W", bound=TickedWorld)


class TickingBackend(abc.ABC, Generic[W]):
    """A `DriveBackend` over a simulated world it ticks every control period.

    The velocity command and odometry are the world's, and the map pose is
    its true pose (a simulated robot is perfectly localised). A subclass says
    how the world's clock goes: `start_clock` and `advance`.

    Args:
        world: The world.
        period: Seconds between two ticks.
        frames: The world's frames, for ``robot.poses``.
    """

    control_period: float
    """Seconds between two ticks (an attribute, not a property: read at every tick)."""

    def __init__(self, world: W, *, period: float, frames: FrameProvider) -> None:
        self.world = world
        self.control_period = period
        self.ticks = 0
        self._frames = frames
        self._robot: Robot | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._virtual: VirtualTimeLoop | None = None  # the loop, when ticks may run ahead
        self._timer: asyncio.TimerHandle | None = None
        self._controllers = Controllers()

    # -- how the world's clock goes ----------------------------------------------------

    @abc.abstractmethod
    def start_clock(self, now: float) -> float:
        """Make the world's clock read ``now`` (the loop's); return when the first tick is due."""

    @abc.abstractmethod
    def advance(self) -> float:
        """Advance the world by one tick (`ticks` counts it already); return when the next is due.

        Computed from whole steps, so that the loop's clock lands exactly on the world's.
        """

    def check_loop(self, loop: asyncio.AbstractEventLoop) -> VirtualTimeLoop | None:
        """The loop as a `VirtualTimeLoop` if ticks may run ahead on it (lockstep), else None.

        Raises:
            PyRobotsError: The backend cannot run on ``loop``.
        """
        return cast("VirtualTimeLoop", loop) if is_virtual(loop) else None

    def not_running(self) -> PyRobotsError:
        """The error for a `control` wait while the backend is not running."""
        return RobotNotRunningError(f"{self!r} is not running; use 'async with robot:' first")

    # -- DriveBackend --------------------------------------------------------------------

    @property
    def sensors(self) -> tuple[Sensor, ...]:
        """The world's sensors."""
        return self.world.sensors

    @property
    def period(self) -> float:
        """Seconds between two ticks: `control_period`."""
        return self.control_period

    @property
    def frames(self) -> FrameProvider:
        """The world's frames."""
        return self._frames

    def set_velocity(self, v: float, w: float) -> None:
        """Command the world's wheels."""
        self.world.set_command(v, w)

    def odom_pose(self) -> Pose2D:
        """The world's dead reckoning, in the ``odom`` frame."""
        return self.world.odom_pose()

    def map_pose(self) -> Pose2D:
        """The world's true pose of the robot, in the ``map`` frame."""
        return self.world.base_pose()

    async def start(self, robot: Robot) -> None:
        """Publish the first readings and start ticking."""
        loop = asyncio.get_running_loop()
        self._virtual = self.check_loop(loop)
        self._robot, self._loop = robot, loop
        first = self.start_clock(loop.time())
        robot.state.write_owned(self.world.read_sensors())
        self.ticks = 0
        self._timer = loop.call_at(first, self._tick)

    async def stop(self) -> None:
        """Stop the wheels and the ticking; fail whatever waits on a controller, now or later.

        An action still running once the robot has stopped (abandoned by the
        watchdog, or cut loose by a second Ctrl-C) gets `not_running`'s
        error from `control` instead of waiting for a tick that never comes.
        """
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.world.set_command(0.0, 0.0)
        self._controllers.cancel()
        self._robot = self._loop = self._virtual = None

    async def control(self, step: Callable[[], bool]) -> None:
        """Call ``step()`` after every tick until it returns True.

        ``step`` reads the fresh sensors and sets the wheel command; the
        motion actions are built on it. Cancelling the wait removes it.
        """
        if self._loop is None:
            raise self.not_running()
        await self._controllers.control(step)

    def _tick(self) -> None:
        robot, loop = self._robot, self._loop
        if robot is None or loop is None:
            return
        # In lockstep, the next tick runs at once, in this callback, while nothing else would
        # run before it (the loop's turn in between would only cost time); the loop turns
        # (polls I/O) at least every TICKS_PER_TURN ticks.
        virtual, world, controllers = self._virtual, self.world, self._controllers
        state = robot.state  # (the robot's one store: it cannot be replaced)
        left = TICKS_PER_TURN
        while True:
            self.ticks += 1
            when = self.advance()
            state.write_owned(world.read_sensors())
            if controllers._waiting:  # (its own package's: no __len__ call at every tick)
                controllers.run()
            left -= 1
            if not left or virtual is None or not virtual.skip_ahead(when):
                break
        self._timer = loop.call_at(when, self._tick)
