"""EventManager: the monitors of one robot (``robot.events``)."""

from __future__ import annotations

from collections.abc import AsyncIterator, Callable
from typing import TYPE_CHECKING, Any, Unpack

from .._exceptions import InvalidConditionError, RobotNotRunningError
from ._callbacks import settle
from ._conditions import (
    Conditions,
    check_blocking,
    check_frequency,
    check_numeric_key,
    check_poll,
    parse,
)
from ._monitor import EventMonitor, Host, label
from ._watch import Feed, Watch, check_buffer

if TYPE_CHECKING:
    from .._core._instrument import Instruments
    from ..actions._executive import Executive
    from ..state import StateStore

Predicate = Callable[[Any], object]
"""A predicate ``f(robot) -> bool``, or an ``async def`` one."""

CANCEL_REASON = "event monitors cancelled"


class EventManager:
    """Creates, keeps and stops the event monitors of one robot (``robot.events``).

    ``robot.whenever``, ``robot.every``, ``robot.on`` and ``robot.wait`` are
    shortcuts to the methods of the same names here. Monitors live until
    stopped, and never outlive ``async with robot``: on exit the robot calls
    `cancel_all`.

    Args:
        robot: The robot: what predicates and unbound action callbacks receive.
        state: The state store watched.
        executive: The robot's executive (its loop, whether it runs, its
            ``cancel_grace``).
        instruments: Where ``MONITOR_FIRED`` events go.
    """

    def __init__(
        self,
        robot: object,
        state: StateStore,
        executive: Executive,
        instruments: Instruments,
    ) -> None:
        self._robot = robot
        self._state = state
        self._executive = executive
        self._instruments = instruments
        self._monitors: dict[EventMonitor, None] = {}
        self._feeds: dict[Feed, None] = {}
        self._next_id = 1
        self._host: Host | None = None

    # -- creating -----------------------------------------------------------------------

    def whenever(
        self,
        var: str | Predicate,
        max_firing_freq: float = 10,
        blocking: bool = True,
        poll: float | None = None,
        **cond: Unpack[Conditions],
    ) -> EventMonitor:
        """Watch ``var`` and fire every time the condition is met; chain ``.do(cb, *args)``.

        Args:
            var: A state key, or a predicate ``f(robot) -> bool`` (sync or
                async) re-evaluated whenever a key it read changes.
            max_firing_freq: Most firings a second of a level condition
                (``value``, ``above``, ``below``, a predicate) while it holds;
                0: unlimited (then it fires on every write that finds it true).
                Edge conditions are never rate-limited.
            blocking: Drop firings while the previous callback still runs
                (True), or run each firing's callback concurrently (False).
            poll: Predicates only: also re-evaluate every ``poll`` seconds
                (for predicates that depend on time).
            **cond: One condition of `Conditions` on a key (``value``,
                ``becomes``, ``above``, ``below``, ``increase``, ``decrease``),
                optionally with ``held_for``; a predicate takes ``held_for`` only.

        Returns:
            The `EventMonitor`, already watching.

        Raises:
            InvalidConditionError: No condition, two, or a wrong one.
            UnknownStateKeyError: ``var`` is not a state key (the closest are listed).
            RobotNotRunningError: The robot is not running.

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> list[float]:
            ...     seen = []
            ...     async with Robot() as robot:
            ...         robot.state.battery = 0.5
            ...         low = robot.whenever("battery", below=0.2)
            ...         low.do(lambda: seen.append(robot.state.battery))
            ...         robot.state.battery = 0.1
            ...         await robot.sleep(0)
            ...     return seen
            >>> asyncio.run(main())
            [0.1]
        """
        freq = check_frequency(max_firing_freq)
        return self._create(var, dict(cond), freq, blocking, poll, one_shot=False)

    every = whenever

    def on(
        self, var: str | Predicate, poll: float | None = None, **cond: Unpack[Conditions]
    ) -> EventMonitor:
        """Like `whenever`, but fire once, then stop monitoring (a one-shot monitor).

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> int:
            ...     async with Robot() as robot:
            ...         robot.state.bumper = False
            ...         monitor = robot.on("bumper", becomes=True)
            ...         for pressed in (True, False, True):
            ...             robot.state.bumper = pressed
            ...         return monitor.firings
            >>> asyncio.run(main())
            1
        """
        return self._create(var, dict(cond), 0.0, True, poll, one_shot=True)

    async def wait(
        self, var: str | Predicate, poll: float | None = None, **cond: Unpack[Conditions]
    ) -> Any:
        """Wait until the condition is met; return the value that met it.

        A level condition (``value``, ``above``, ``below``, a predicate) that
        already holds returns at the next loop iteration; an edge condition
        (``becomes``, ``increase``, ``decrease``) waits for the next change
        into it. With ``held_for``, the hold is counted from the call.
        Callers own the deadline: ``async with asyncio.timeout(5): ...``.

        Raises:
            InvalidConditionError: No condition, two, or a wrong one.
            UnknownStateKeyError: ``var`` is not a state key.
            RobotNotRunningError: The robot is not running.
            StateError: The monitors were stopped (`cancel_all`) before it was met.
        """
        monitor = self.on(var, poll, **cond)
        try:
            return await monitor.wait()
        finally:
            monitor.stop_monitoring()

    def watch(self, key: str, buffer: int = 64) -> AsyncIterator[Any]:
        """Iterate over every change of ``key`` (each write of a different value), in order.

        Writes are buffered from this call on; the iteration ends cleanly when
        the robot stops or `cancel_all` runs. A consumer more than ``buffer``
        values behind loses the oldest (counted, with one warning).

        Raises:
            UnknownStateKeyError: ``key`` is not a state key (the closest are listed).
            ValueError: ``buffer`` is not a positive int.
            RobotNotRunningError: The robot is not running.

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> list[bool]:
            ...     seen = []
            ...     async with Robot() as robot:
            ...         robot.state.bumper = False
            ...         changes = robot.watch("bumper")
            ...         for pressed in (True, True, False):  # True twice: one change
            ...             robot.state.bumper = pressed
            ...         async for pressed in changes:
            ...             seen.append(pressed)
            ...             if not pressed:
            ...                 break
            ...     return seen
            >>> asyncio.run(main())
            [True, False]
        """
        size = check_buffer(buffer)
        host = self._running_host(key)
        self._state.require(key)
        feed = Feed(host.loop, self._state, key, size, host.log)
        self._feeds[feed] = None
        return Watch(feed, self._forget_feed)

    def _forget_feed(self, feed: Feed) -> None:
        self._feeds.pop(feed, None)

    def _create(
        self,
        var: str | Predicate,
        cond: dict[str, object],
        freq: float,
        blocking: object,
        poll: object,
        *,
        one_shot: bool,
    ) -> EventMonitor:
        key = _key_of(var)
        condition = parse(key, cond)
        every_seconds = check_poll(poll, key)
        blocks = check_blocking(blocking)
        host = self._running_host(label(var))
        if key is not None:
            self._state.require(key)
            check_numeric_key(key, condition, self._state.get(key))
        ident = self._next_id
        self._next_id += 1
        monitor = EventMonitor(
            host, ident, var, condition,
            max_firing_freq=freq, blocking=blocks, poll=every_seconds, one_shot=one_shot,
        )  # fmt: skip
        self._monitors[monitor] = None
        return monitor

    def _running_host(self, what: str) -> Host:
        executive = self._executive
        if not executive.is_running:
            msg = (
                f"cannot monitor {what!r}: {self._robot!r} is not running; "
                "create monitors inside 'async with robot:'"
            )
            raise RobotNotRunningError(msg)
        loop = executive.check_loop(f"monitor {what!r}")
        if self._host is None or self._host.loop is not loop:
            self._host = Host(
                self._robot, self._state, loop, self._instruments, executive.cancel_grace,
                self._forget, executive.log_scope.logger("pyrobots_aio.events"),
            )  # fmt: skip
        return self._host

    def _forget(self, monitor: EventMonitor) -> None:
        self._monitors.pop(monitor, None)

    # -- stopping ----------------------------------------------------------------------

    def monitors(self) -> list[EventMonitor]:
        """The monitors still watching or running a callback, oldest first."""
        return list(self._monitors)

    def stop_all_monitoring(self) -> None:
        """Stop every monitor; running callbacks are left to finish."""
        for monitor in list(self._monitors):
            monitor.stop_monitoring()

    async def cancel_all(self, reason: str | None = None) -> None:
        """Stop every monitor and `watch`, cancel running callbacks and wait until they are done.

        Bounded like actions' cleanup (``cancel_grace``, twice at most), and it
        completes even if the calling task is cancelled meanwhile.
        """
        for feed in list(self._feeds):
            feed.close()
        monitors = list(self._monitors)
        for monitor in monitors:
            monitor.stop_monitoring()
        runners = [m._runner for m in monitors]  # the manager owns its monitors
        for runner in runners:
            runner.cancel(reason or CANCEL_REASON)
        await settle(runners, self._executive.cancel_grace)

    def __len__(self) -> int:
        return len(self._monitors)

    def __repr__(self) -> str:
        return f"<EventManager {len(self._monitors)} monitors>"


def _key_of(var: object) -> str | None:
    if isinstance(var, str):
        return var
    if callable(var):
        return None
    msg = (
        f"a monitor watches a state key (str) or a predicate f(robot) -> bool, "
        f"got {var!r} ({type(var).__name__})"
    )
    raise InvalidConditionError(msg)
