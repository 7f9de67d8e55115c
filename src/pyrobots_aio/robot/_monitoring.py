"""The robot's state-facing methods (pyRobots vocabulary), kept apart from the executive.

``whenever``/``every``/``on``/``wait`` are shortcuts to ``robot.events``
(`EventManager`), where monitors are made and kept.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Self, Unpack

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable

    from ..events import Conditions, EventManager, EventMonitor
    from ..state import StateStore


class StateMethods:
    """Methods of `Robot` that read or watch ``robot.state``."""

    state: StateStore
    events: EventManager

    def filtered(self, name: str, value: float, window: int = 10) -> float:
        """Add ``value`` to the moving window ``name`` and return the window's mean.

        pyRobots' ``robot.filtered``: smooth a noisy reading before acting on it.

        Examples:
            >>> from pyrobots_aio import Robot
            >>> robot = Robot()
            >>> robot.filtered("sonar", 1.0), robot.filtered("sonar", 2.0)
            (1.0, 1.5)
        """
        return self.state.filtered(name, value, window)

    def whenever(
        self,
        var: str | Callable[[Self], object],
        max_firing_freq: float = 10,
        blocking: bool = True,
        poll: float | None = None,
        **cond: Unpack[Conditions],
    ) -> EventMonitor:
        """Fire every time a condition on the state is met; chain ``.do(callback, *args)``.

        ``var`` is a state key with one condition (``value=``, ``becomes=``,
        ``above=``, ``below=``, ``increase=``, ``decrease=``, optionally with
        ``held_for=``), or a predicate ``f(robot) -> bool`` (sync or async).
        See `EventManager.whenever` for every parameter.

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot, action
            >>> @action
            ... async def say(robot: Robot, text: str) -> None:
            ...     robot.state.said = text
            >>> async def main() -> str:
            ...     async with Robot() as robot:
            ...         robot.state.update(bumper=False, said="")
            ...         robot.whenever("bumper", becomes=True).do(say, "ouch")
            ...         robot.state.bumper = True
            ...         await robot.sleep(0.01)
            ...         return robot.state.said
            >>> asyncio.run(main())
            'ouch'
        """
        return self.events.whenever(var, max_firing_freq, blocking, poll, **cond)

    def every(
        self,
        var: str | Callable[[Self], object],
        max_firing_freq: float = 10,
        blocking: bool = True,
        poll: float | None = None,
        **cond: Unpack[Conditions],
    ) -> EventMonitor:
        """Another name of `whenever` (pyRobots' ``every``)."""
        return self.events.whenever(var, max_firing_freq, blocking, poll, **cond)

    def on(
        self,
        var: str | Callable[[Self], object],
        poll: float | None = None,
        **cond: Unpack[Conditions],
    ) -> EventMonitor:
        """Fire once when the condition is met, then stop monitoring (a one-shot monitor).

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> list[str]:
            ...     said = []
            ...     async with Robot() as robot:
            ...         robot.state.docked = True
            ...         robot.on("docked", becomes=False).do(said.append, "bye")
            ...         for docked in (False, True, False):
            ...             robot.state.docked = docked
            ...         await robot.sleep(0)
            ...     return said
            >>> asyncio.run(main())
            ['bye']
        """
        return self.events.on(var, poll, **cond)

    async def wait(
        self,
        var: str | Callable[[Self], object],
        poll: float | None = None,
        **cond: Unpack[Conditions],
    ) -> Any:
        """Wait until the condition is met; return the value that met it.

        A level condition that already holds returns at once (at the next loop
        iteration); an edge condition (``becomes``, ``increase``,
        ``decrease``) waits for the next change into it. Callers own the
        deadline: ``async with asyncio.timeout(5): await robot.wait(...)``.

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> float:
            ...     async with Robot() as robot:
            ...         robot.state.battery = 1.0
            ...         async def drain() -> None:
            ...             while robot.state.battery > 0:
            ...                 await robot.sleep(0.01)
            ...                 robot.state.battery = round(robot.state.battery - 0.25, 2)
            ...         task = asyncio.create_task(drain())
            ...         low = await robot.wait("battery", below=0.3)
            ...         await task
            ...         return low
            >>> asyncio.run(main())
            0.25
        """
        return await self.events.wait(var, poll, **cond)

    def watch(self, key: str, buffer: int = 64) -> AsyncIterator[Any]:
        """Every change of state ``key``, as an async iterator ending when the robot stops.

        ``async for pressed in robot.watch("bumper"): ...`` sees each write of a
        new value, in order, from the call on; see `EventManager.watch`.
        """
        return self.events.watch(key, buffer)
