"""The simulator's backend: a `TickingBackend` stepping MuJoCo every control tick.

The ticking itself (a loop callback per tick, lockstep ticks back to back)
is `pyrobots_aio.motion.TickingBackend`'s; here, the simulator's clock: a
tick is a whole number of physics steps, and the world's clock reads the
loop's from the start of each run (the physics pauses between runs).

Robots sharing a world (``SimWorld(robots=N)``) each have a backend, and
their ticks fall at the same times: a tick steps the world up to its own
step count, so the first robot's tick at a time steps the physics and the
others' at that time only read it. The first to start sets the clock; the
others join it.
"""

from __future__ import annotations

import asyncio
from typing import cast

from .._exceptions import LockstepError
from ..loops import VirtualTimeLoop, is_virtual
from ..lowlevel import finite
from ..motion import TickingBackend
from ._frames import WorldFrames
from ._world import SimWorld

__all__ = ["SimBackend"]


class SimBackend(TickingBackend[SimWorld]):
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
        super().__init__(world, period=steps * world.physics_dt, frames=WorldFrames(world))
        self.realtime = realtime
        self.steps_per_tick = steps
        self._next_step = 0  # the world's step count at this robot's next tick

    def check_loop(self, loop: asyncio.AbstractEventLoop) -> VirtualTimeLoop | None:
        """The loop, in lockstep (it must be virtual); None in real time.

        Raises:
            LockstepError: A lockstep robot on an ordinary loop.
        """
        if self.realtime:
            return None
        if not is_virtual(loop):
            msg = (
                "this simulated robot runs in lockstep virtual time (realtime=False), but the "
                "event loop is an ordinary one; start it with pyrobots_aio.sim.run(main) or the "
                "pytest marker @pytest.mark.virtual_time, or pass realtime=True"
            )
            raise LockstepError(msg)
        return cast("VirtualTimeLoop", loop)

    def not_running(self) -> LockstepError:
        """A controller's wait on a simulator that is not running fails at once."""
        return LockstepError("the simulated robot is not running; use 'async with robot:' first")

    def start_clock(self, now: float) -> float:
        """The world's clock reads the loop's ``now`` (unless it runs already, for another robot).

        The first tick is one tick's steps on.
        """
        world = self.world
        world.enter_run(now)
        self._next_step = world.steps + self.steps_per_tick
        return world.time_after(self.steps_per_tick)

    def advance(self) -> float:
        """Step the physics to this tick (unless another robot's did); the next is a tick on."""
        world = self.world
        behind = self._next_step - world.steps
        if behind > 0:
            world.step(behind)
        self._next_step += self.steps_per_tick
        return world.time_at(self._next_step)

    async def stop(self) -> None:
        """Stop ticking (`TickingBackend.stop`); the world's clock no longer counts this robot."""
        await super().stop()
        self.world.leave_run()

    def __repr__(self) -> str:
        mode = "realtime" if self.realtime else "lockstep"
        return f"<SimBackend {mode} {1 / self.period:g} Hz tick {self.ticks}>"
