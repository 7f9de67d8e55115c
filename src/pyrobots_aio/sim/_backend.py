"""The simulator's control loop: step physics and publish sensors every control tick.

Each tick is a plain loop callback (no task) scheduled with ``call_at`` at the
world's time after the tick's physics steps (``start + k * period``, computed
from whole steps), so lockstep time stays exact and equal to the world's. A tick
steps MuJoCo, writes every sensor to ``robot.state`` in one batch (monitors
see each tick's values), then runs the controllers the motion actions
registered. In lockstep the loop's virtual clock jumps from tick to tick; in
real time the same code runs against the wall clock.

In lockstep, when nothing else would run before the next tick (no callback
ready, no earlier timer), the next tick runs at once in the same callback: the
loop's turn in between would only have polled I/O. The ticks, and everything
they compute, are the same; the loop still turns every `TICKS_PER_TURN` ticks.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, cast

from .._core._numbers import finite
from .._exceptions import LockstepError
from ..loops import VirtualTimeLoop, is_virtual
from ..motion import Controllers

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..robot import Robot
    from ._world import SimWorld

_log = logging.getLogger("pyrobots_aio.sim")

TICKS_PER_TURN = 10
"""Lockstep ticks run back to back at most (when nothing else is due between them)."""


class SimBackend:
    """Runs a `SimWorld` in step with the event loop and publishes it to a robot.

    Args:
        world: The physics.
        control_rate: Control ticks per second (sensors published, controllers run).
        realtime: False for lockstep virtual time (the loop must be virtual),
            True for the wall clock.
    """

    def __init__(self, world: SimWorld, *, control_rate: float = 50.0, realtime: bool = False):
        finite(  # control_rate kept as given: the message below shows it as written
            "control_rate",
            control_rate,
            positive=True,
            must="a positive number of ticks per second",
        )
        steps = round(1.0 / (control_rate * world.physics_dt))
        if steps < 1 or abs(steps * world.physics_dt * control_rate - 1.0) > 1e-9:
            msg = (
                f"control_rate {control_rate!r} Hz is not a whole number of physics steps of "
                f"{world.physics_dt} s; pick a rate such as 50 or 100"
            )
            raise ValueError(msg)
        self.world = world
        self.realtime = realtime
        self.steps_per_tick = steps
        self.period = steps * world.physics_dt
        self.ticks = 0
        self._robot: Robot | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._virtual: VirtualTimeLoop | None = None  # the loop, in lockstep
        self._timer: asyncio.TimerHandle | None = None
        self._controllers = Controllers()

    async def start(self, robot: Robot) -> None:
        """Publish the first sensor readings and start ticking."""
        loop = asyncio.get_running_loop()
        if not self.realtime and not is_virtual(loop):
            msg = (
                "this simulated robot runs in lockstep virtual time (realtime=False), but the "
                "event loop is an ordinary one; start it with pyrobots_aio.sim.run(main) or the "
                "pytest marker @pytest.mark.virtual_time, or pass realtime=True"
            )
            raise LockstepError(msg)
        self._robot, self._loop = robot, loop
        self._virtual = None if self.realtime else cast("VirtualTimeLoop", loop)
        # The world's clock reads the loop's (the physics pauses between runs).
        self.world.set_time(loop.time())
        robot.state.write_owned(self.world.read_sensors())
        self.ticks = 0
        self._schedule(loop)

    async def stop(self) -> None:
        """Stop the wheels and the ticking; fail whatever waits on a controller, now or later.

        An action still running once the robot has stopped (abandoned by the
        watchdog, or cut loose by a second Ctrl-C) gets `LockstepError` from
        `control` instead of waiting for a tick that never comes.
        """
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.world.stop()
        self._controllers.cancel()
        self._robot = self._loop = self._virtual = None

    async def control(self, controller: Callable[[], bool]) -> None:
        """Call ``controller()`` after every tick until it returns True.

        The controller reads the fresh sensors and sets the wheel command; the
        motion actions are built on it. Cancelling the wait removes it.
        """
        if self._loop is None:
            msg = "the simulated robot is not running; use 'async with robot:' first"
            raise LockstepError(msg)
        await self._controllers.control(controller)

    def _tick(self) -> None:
        robot, loop = self._robot, self._loop
        if robot is None or loop is None:
            return
        # In lockstep, the next tick runs at once, in this callback, while nothing else would
        # run before it (the loop's turn in between would only cost time); the loop turns
        # (polls I/O) at least every TICKS_PER_TURN ticks.
        virtual = self._virtual
        left = TICKS_PER_TURN
        while True:
            self.ticks += 1
            world = self.world
            world.step(self.steps_per_tick)
            when = world.time_after(self.steps_per_tick)
            robot.state.write_owned(world.read_sensors())
            if self._controllers:
                self._run_controllers()
            left -= 1
            if not left or virtual is None or not virtual.skip_ahead(when):
                break
        self._timer = loop.call_at(when, self._tick)

    def _schedule(self, loop: asyncio.AbstractEventLoop) -> None:
        self._timer = loop.call_at(self.world.time_after(self.steps_per_tick), self._tick)

    def _run_controllers(self) -> None:
        self._controllers.run()

    def __repr__(self) -> str:
        mode = "realtime" if self.realtime else "lockstep"
        return f"<SimBackend {mode} {1 / self.period:g} Hz tick {self.ticks}>"
