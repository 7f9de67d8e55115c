"""EventMonitor: one watched condition, its firings, its callback and its waiters."""

from __future__ import annotations

import contextvars
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self

from .._core._events import MonitorFired
from .._exceptions import StateError
from ..actions import current_action
from ._callbacks import CallbackRunner, describe, settle
from ._sources import KeySource, PredicateSource
from ._trigger import Trigger

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

    from .._core._instrument import Instruments
    from .._core._logging import ScopedLogger
    from ..state import StateStore
    from ._conditions import Condition

_JSON_SCALARS = (bool, int, float, str, type(None))


@dataclass(frozen=True, slots=True)
class Host:
    """What monitors need from their robot during one ``async with robot``."""

    robot: object
    store: StateStore
    loop: asyncio.AbstractEventLoop
    instruments: Instruments
    grace: float
    forget: Callable[[EventMonitor], None]
    log: ScopedLogger


class EventMonitor:
    """A condition over the robot's state, watched from creation until stopped.

    Created by ``robot.whenever()``, ``robot.every()`` and ``robot.on()``;
    `do` registers what to run when it fires, and chains: ``.do(a).do(b)``
    runs both. A monitor is active from creation: a level condition that
    already holds fires at the next loop iteration, after the ``.do()`` calls
    chained to the creation have run; firings before ``.do()`` run no
    callback (they still wake `wait`).

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot
        >>> async def main() -> list[str]:
        ...     said = []
        ...     async with Robot() as robot:
        ...         robot.state.bumper = False
        ...         monitor = robot.whenever("bumper", becomes=True).do(said.append, "ouch")
        ...         robot.state.bumper = True
        ...         await robot.sleep(0)
        ...         await monitor.close()
        ...     return said
        >>> asyncio.run(main())
        ['ouch']
    """

    def __init__(
        self,
        host: Host,
        ident: int,
        var: str | Callable[[Any], object],
        condition: Condition,
        *,
        max_firing_freq: float,
        blocking: bool,
        poll: float | None,
        one_shot: bool,
    ) -> None:
        self._host = host
        self._id = ident
        self._var = var
        self._condition = condition
        self._max_firing_freq = max_firing_freq
        self._blocking = blocking
        self._one_shot = one_shot
        self._monitoring = True
        self._firings = 0
        self._waiters: list[asyncio.Future[Any]] = []
        self._name = f"{label(var)} {condition.describe()}".strip()
        context = contextvars.copy_context()
        context.run(current_action.set, None)  # callbacks run in the robot's root scope
        loop = host.loop
        self._runner = CallbackRunner(
            loop, host.robot, context, self._settled, host.log, label=f"monitor {self._name!r}"
        )
        period = 1.0 / max_firing_freq if max_firing_freq and not one_shot else 0.0
        self._trigger = Trigger(
            loop,
            self._on_fire,
            edge=condition.edge,
            rearm=condition.relative,
            held_for=condition.held_for,
            period=period,
            context=context,
        )
        self._source: KeySource | PredicateSource
        self._rebase: Callable[[Any], None] | None = None
        if isinstance(var, str):
            self._source = KeySource(host.store, var, condition, self._trigger, self._name)
            if condition.relative:
                self._rebase = self._source.rebase
            if not condition.edge:
                loop.call_soon(self._source.observe_first, host.store, context=context)
        else:
            self._source = PredicateSource(
                loop, host.store, host.robot, var, trigger=self._trigger, runner=self._runner,
                poll=poll, label=self._name,
            )  # fmt: skip
            try:
                self._source.start()
            except BaseException:
                self._stop()
                raise

    # -- introspection ---------------------------------------------------------------

    @property
    def id(self) -> int:
        """The monitor's number, unique within its robot."""
        return self._id

    @property
    def name(self) -> str:
        """The watched key (or predicate name) and condition, e.g. ``bumper becomes=True``."""
        return self._name

    @property
    def var(self) -> str | Callable[[Any], object]:
        """The watched state key or predicate."""
        return self._var

    @property
    def condition(self) -> str:
        """The condition as keywords, e.g. ``below=0.3 held_for=2.0``."""
        return self._condition.describe()

    @property
    def monitoring(self) -> bool:
        """Whether it still watches (False once stopped, and after a one-shot fired)."""
        return self._monitoring

    @property
    def firings(self) -> int:
        """How many times it has fired (dropped callbacks included)."""
        return self._firings

    @property
    def callbacks(self) -> tuple[Callable[..., object], ...]:
        """The callbacks given to `do`, in the order they start at each firing."""
        return self._runner.callbacks

    @property
    def running(self) -> bool:
        """Whether a callback is queued or running."""
        return self._runner.busy

    @property
    def blocking(self) -> bool:
        """Whether firings are dropped while the callback runs."""
        return self._blocking

    @property
    def max_firing_freq(self) -> float:
        """The most firings a second of a level condition (0: unlimited)."""
        return self._max_firing_freq

    @property
    def one_shot(self) -> bool:
        """Whether it stops after its first firing (``robot.on``)."""
        return self._one_shot

    # -- using ------------------------------------------------------------------------

    def do(self, callback: Callable[..., object], *args: Any) -> Self:
        """Run ``callback(*args)`` at each firing, after those already given; return this monitor.

        ``callback`` may be an action (started in the robot's root scope; an
        unbound action receives the robot first, as every action call does),
        a coroutine function (run as a task owned by the monitor) or a plain
        function (called from the event loop, never inside the state write).
        One that raises is logged on ``pyrobots_aio.events`` and the monitor
        goes on.

        Calls chain, as in pyRobots: ``robot.whenever(...).do(a).do(b)``
        starts ``a`` then ``b`` at each firing, both at the next loop
        iteration (not ``b`` once ``a`` is done: one coroutine function
        awaiting both does that). Each is isolated from the others: one that
        raises is logged and the others run. With ``blocking=True`` a firing
        is dropped while any of them still runs.

        Raises:
            TypeError: ``callback`` is not callable.
        """
        self._runner.add(callback, args)
        return self

    async def wait(self) -> Any:
        """Wait for the next firing; return the value that fired it.

        Raises:
            StateError: The monitor is stopped, or stops before it fires.
        """
        if not self._monitoring:
            msg = f"monitor {self._name!r} is stopped; it will not fire again"
            raise StateError(msg)
        fut = self._host.loop.create_future()
        self._waiters.append(fut)
        try:
            return await fut
        finally:
            if fut in self._waiters:
                self._waiters.remove(fut)

    def stop_monitoring(self) -> None:
        """Stop watching; a callback already running finishes (plain call, idempotent)."""
        if self._monitoring:
            self._stop()
            self._settled()

    async def close(self) -> None:
        """Stop watching, cancel a running callback and wait until it is done.

        The wait is bounded like actions' cleanup: a callback still running a
        ``cancel_grace`` after cancellation is cancelled again (with a warning),
        and abandoned after a second grace (with an error).
        """
        self.stop_monitoring()
        self._runner.cancel(f"monitor {self._name!r} closed")
        await settle([self._runner], self._host.grace)

    # -- firing --------------------------------------------------------------------------

    def _on_fire(self, value: Any) -> None:
        if self._rebase is not None:
            self._rebase(value)
        self._firings += 1
        runner = self._runner
        if not runner.has_callbacks:
            status = "none"
        elif self._blocking and runner.busy:
            status = "dropped"
        else:
            status = "started"
        if self._host.instruments:
            self._emit(value, status)
        if status == "started":
            runner.start()
        if self._waiters:
            waiters, self._waiters = self._waiters, []
            for fut in waiters:
                if not fut.done():
                    fut.set_result(value)
        if self._one_shot:
            self.stop_monitoring()

    def _emit(self, value: Any, status: str) -> None:
        host = self._host
        event = MonitorFired(
            host.loop.time(),
            None,
            self._name,
            monitor=self._id,
            var=label(self._var),
            condition=self.condition,
            value=value if isinstance(value, _JSON_SCALARS) else repr(value),
            callback=status,
        )
        host.instruments.emit(event)

    # -- stopping --------------------------------------------------------------------------

    def _stop(self) -> None:
        self._monitoring = False
        self._trigger.stop()
        self._source.stop()
        waiters, self._waiters = self._waiters, []
        for fut in waiters:
            if not fut.done():
                fut.set_exception(StateError(f"monitor {self._name!r} stopped before it fired"))

    def _settled(self) -> None:
        if not self._monitoring and self._runner.settled:
            self._host.forget(self)

    def __repr__(self) -> str:
        state = "monitoring" if self._monitoring else "stopped"
        callbacks = self._runner.callbacks
        does = ""
        if callbacks:
            plural = "s" if len(callbacks) > 1 else ""
            does = f", callback{plural} {', '.join(describe(c) for c in callbacks)}"
        if self._runner.busy:
            does += " running"
        return f"<EventMonitor #{self._id} {self._name!r} {state}, fired {self._firings}{does}>"


def label(var: str | Callable[[Any], object]) -> str:
    """How a monitor names what it watches: the key, or the predicate's ``__name__``."""
    return var if isinstance(var, str) else describe(var, qualified=False)
