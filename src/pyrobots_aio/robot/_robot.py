"""Robot: the composition root, an async context manager around the executive.

``async with Robot() as robot:`` opens the root scope and starts what the
robot runs (signal handling, the loop watchdog, the live view, extensions, the
backend), each step pushed on one `contextlib.AsyncExitStack`; leaving unwinds
it: the monitors stop, every action is cancelled (bounded by
``cancel_grace``), then the backend stops, children before parents. Nothing
starts in ``__init__``.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import logging
import math
import types
from typing import TYPE_CHECKING, Any, Self, TypeVar, TypeVarTuple

from .._core._blockwatch import DEFAULT_BLOCK_THRESHOLD, BlockWatch, check_block_threshold
from .._core._instrument import Instrument, Instruments
from .._core._logging import LogScope, check_level
from .._core._loops import current_loop, no_asyncio_loop
from .._core._numbers import finite
from .._core._signals import SignalStop
from .._core._waiting import sleep_until
from .._exceptions import ActionDefinitionError, ActionError, EventLoopError, PyRobotsError
from ..actions import Action, ActionInfo, BoundAction, action, current_action
from ..actions._executive import Executive
from ..actions._info import render_tree as _render_tree
from ..events import EventManager
from ..poses import PoseManager
from ..resources import ResourceManager
from ..state import StateStore
from ..telemetry import LiveView
from ._estop import EmergencyStop
from ._monitoring import StateMethods
from ._offloop import Workers, blocking_action

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Iterable, Mapping

    from ..actions import ActionHandle
    from ._backend import Backend

T = TypeVar("T")
Ts = TypeVarTuple("Ts")

SHUTDOWN_REASON = "robot shutting down"


class Robot(StateMethods, EmergencyStop):
    """A robot: runs actions, arbitrates resources, watches its state.

    Args:
        actions: Modules or action functions to attach: each becomes a bound
            method of this robot (``robot.walk(0.2)``). Plain ``async def``
            functions are made actions.
        dummy: A flag subclasses read to skip real hardware (pyRobots' dummy mode).
        max_actions: Most actions allowed to run at once (None: no limit).
        cancel_grace: Seconds a cancelled action gets for its cleanup before it is
            cancelled again; after a second grace it is abandoned.
        instruments: Instruments receiving every executive event (recorders).
        backend: The backend that connects this robot to hardware or a simulator.
        serve: A TCP port: while the robot runs, stream it live on 127.0.0.1 over
            Foxglove's WebSocket protocol (the ``live`` extra); 0 picks a free port,
            which ``robot.live.port`` tells once the robot runs. Or a `LiveView`
            of your own, which the robot streams to while it runs and leaves
            serving after (Foxglove stays connected; ``live.stop()`` ends it).
        block_threshold: Seconds the event loop may go without turning before a
            watchdog thread logs a WARNING naming the action that blocks it, with
            its ``file:line`` and stack, and records a ``loop.blocked`` event
            (real time, also in lockstep simulation); None: no watchdog.
        handle_signals: While the robot runs in the main thread, take SIGINT and
            SIGTERM over unless the program handles them already: the first
            cancels the task that entered ``async with robot`` (an orderly
            shutdown, cleanup bounded by ``cancel_grace``), a second cuts the
            cleanup short, a third gets Python's default; once that task is
            done, `KeyboardInterrupt` (SIGINT) or ``SystemExit(143)`` (SIGTERM)
            comes out of the event loop if the cancellation ended it, not if
            the program caught it, inside the block or around it, and went on
            (``asyncio.run``'s rule). The count goes on while the program
            unwinds, until the event loop closes: a second signal never ends
            the process in the middle of a recorder's close.
            False: leave the signals alone (see `pyrobots_aio.cli.stop_on_signals`).

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot, action
        >>> @action
        ... async def double(robot: Robot, x: int) -> int:
        ...     await robot.sleep(0.01)
        ...     return 2 * x
        >>> async def main() -> int:
        ...     async with Robot(actions=[double]) as robot:
        ...         return await robot.double(21)
        >>> asyncio.run(main())
        42
    """

    def __init__(
        self,
        *,
        actions: Iterable[object] = (),
        dummy: bool = False,
        max_actions: int | None = None,
        cancel_grace: float = 2.0,
        instruments: Iterable[Instrument] = (),
        backend: Backend | None = None,
        serve: int | LiveView | None = None,
        block_threshold: float | None = DEFAULT_BLOCK_THRESHOLD,
        handle_signals: bool = True,
    ) -> None:
        flag: object = handle_signals  # checked at run time: the annotation promises nothing
        if not isinstance(flag, bool):
            msg = f"handle_signals must be True or False, got {flag!r}"
            raise TypeError(msg)
        self.handle_signals = handle_signals
        self._block_threshold = check_block_threshold(block_threshold)
        self._blockwatch: BlockWatch | None = None
        self._workers: Workers | None = None  # robot.to_thread's threads, from its first call
        self._attached: dict[str, Action[Any, Any, Any]] = {}
        self._extensions: dict[str, Backend] = {}
        self._running = contextlib.AsyncExitStack()  # what __aexit__ undoes
        self.dummy = dummy
        self.instruments = Instruments()
        for instrument in instruments:
            self.instruments.add(instrument)
        self._log_scope = LogScope()
        self.resources: ResourceManager[ActionHandle[Any]] = ResourceManager(self.instruments)
        # Runs the robot's actions; ``@action`` finds it here (the library's to call, not a
        # program's: public only for the layers above, as `actions._decorator.Runner` says).
        self.executive = Executive(
            self,
            resources=self.resources,
            max_actions=max_actions,
            cancel_grace=cancel_grace,
            instruments=self.instruments,
            log=self._log_scope,
        )
        self._state = StateStore()
        self.events = EventManager(self, self._state, self.executive, self.instruments)
        self.poses = PoseManager()
        self._backend = backend
        self.live = serve if isinstance(serve, LiveView) or serve is None else LiveView(serve)
        self._owns_live = not isinstance(serve, LiveView)
        for item in actions:
            self._attach(item)

    # -- attaching actions ------------------------------------------------

    def _attach(self, item: object) -> None:
        if isinstance(item, types.ModuleType):
            found = [v for v in vars(item).values() if isinstance(v, Action)]
            if not found:
                msg = f"module {item.__name__!r} defines no @action; nothing to attach"
                raise ActionDefinitionError(msg)
            for act in found:
                self._attach_one(act)
        elif isinstance(item, Action):
            self._attach_one(item)
        else:
            self._attach_one(action(item))  # type: ignore[call-overload]

    def _attach_one(self, act: Action[Any, Any, Any]) -> None:
        if self._name_taken(act.name):
            msg = f"cannot attach action {act.name!r}: {type(self).__name__} already has that name"
            raise ActionDefinitionError(msg)
        known = self._attached.get(act.name)
        if known is not None and known is not act:
            msg = (
                f"cannot attach action {act.name!r} from {act.fn.__module__}: an action of "
                f"that name from {known.fn.__module__} is attached already; rename one of them"
            )
            raise ActionDefinitionError(msg)
        self._attached[act.name] = act

    def _name_taken(self, name: str) -> bool:
        """Whether ``name`` is an attribute of the robot or one of its extensions."""
        return hasattr(type(self), name) or name in vars(self) or name in self._extensions

    def __getattr__(self, name: str) -> Any:
        """An attached action, bound to the robot (a `BoundAction`), or an extension."""
        extensions = self.__dict__.get("_extensions", {})
        if name in extensions:
            return extensions[name]
        attached = self.__dict__.get("_attached", {})
        if name in attached:
            return BoundAction(attached[name], self)
        msg = f"{type(self).__name__!r} has no attribute or action {name!r}"
        if attached:
            msg += f"; attached actions: {sorted(attached)}"
        raise AttributeError(msg)

    # -- state ------------------------------------------------------------

    @property
    def state(self) -> StateStore:
        """The robot's state store: write values into it; it cannot be replaced.

        Monitors and backends hold this very store, so ``robot.state = {...}``
        raises; write ``robot.state.update({...})`` instead.
        """
        return self._state

    @state.setter
    def state(self, value: object) -> None:
        msg = (
            f"robot.state cannot be replaced (got {type(value).__name__}): monitors and the "
            "backend watch this store; write values into it, e.g. robot.state.update(...)"
        )
        raise AttributeError(msg)

    # -- lifecycle --------------------------------------------------------

    @property
    def is_running(self) -> bool:
        """Whether the robot is running (inside ``async with robot``)."""
        return self.executive.is_running

    async def __aenter__(self) -> Self:
        if self.executive.is_running:
            msg = f"{self!r} is already running; enter 'async with robot:' once at a time"
            raise PyRobotsError(msg)
        loop = current_loop()
        if loop is None:
            raise no_asyncio_loop(f"run {type(self).__name__}")
        async with contextlib.AsyncExitStack() as stack:
            await self._open(stack, loop)
            self._running = stack.pop_all()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: types.TracebackType | None,
    ) -> None:
        running, self._running = self._running, contextlib.AsyncExitStack()
        await running.__aexit__(exc_type, exc, tb)

    async def _open(
        self, stack: contextlib.AsyncExitStack, loop: asyncio.AbstractEventLoop
    ) -> None:
        """Start everything the robot runs, each step's undoing pushed on ``stack``.

        The stack unwinds in reverse, each step even if the one before was
        cancelled (it finishes its bounded wait, then re-raises): the monitors,
        then the actions (children before parents), the backend, the extensions
        and the live view, the state's loop, ``to_thread``'s idle threads, the
        loop watchdog (it sees the whole exit) and the signals last. A start
        that fails unwinds what started before it.
        """
        if self.handle_signals:
            stack.enter_context(SignalStop())
        if self._block_threshold is not None:
            self._watch_loop(loop, self._block_threshold)
            stack.callback(self._unwatch_loop)
        stack.callback(self._close_workers)
        self._state.bind(loop)
        stack.callback(self._state.bind, None)
        self.executive.open(loop)
        stack.push_async_callback(self._close_actions)  # if a start fails (a run closed it above)
        if self.live is not None:
            self.live.start(self)
            stack.callback(self.live.stop if self._owns_live else self.live.detach)
        for part in self._parts():
            await part.start(self)
            stack.push_async_callback(part.stop)
        stack.push_async_callback(self._close_actions)
        stack.push_async_callback(self.events.cancel_all)

    def _parts(self) -> list[Backend]:
        """What starts with the robot, in order: its extensions, then its backend."""
        parts = list(self._extensions.values())
        if self._backend is not None:
            parts.append(self._backend)
        return parts

    async def _close_actions(self) -> None:
        """Cancel every action and wait for them; no new root action starts from here on."""
        if self.executive.is_running:
            await self.executive.close(SHUTDOWN_REASON)

    @property
    def backend(self) -> Backend | None:
        """The backend connecting the robot to hardware or a simulator (None: a bare robot).

        It starts inside ``async with robot``, after the extensions, and stops
        once every action is done (`Backend`).
        """
        return self._backend

    @property
    def extensions(self) -> Mapping[str, Backend]:
        """The parts given with `add_extension`, by name (read-only)."""
        return types.MappingProxyType(self._extensions)

    def add_extension(self, name: str, extension: Backend) -> None:
        """Give the robot a part that runs with it, reachable as ``robot.<name>``.

        For what a program adds to a robot it did not write, such as a ROS 2
        node (`pyrobots_aio.ros2.attach_ros2`). Extensions start inside
        ``async with robot`` in the order given, before the robot's backend,
        and stop after it, once every action is done.

        Raises:
            PyRobotsError: The robot is running, or ``name`` is taken (an
                attribute, an attached action or another extension).

        Examples:
            >>> class Lamp:
            ...     async def start(self, robot: Robot) -> None:
            ...         robot.state.lamp = "on"
            ...     async def stop(self) -> None:
            ...         pass
            >>> async def main() -> str:
            ...     robot = Robot()
            ...     robot.add_extension("lamp", Lamp())
            ...     async with robot:
            ...         return robot.state.lamp
            >>> asyncio.run(main())
            'on'
        """
        if self.is_running:
            msg = f"add extensions before 'async with robot:', not while {self!r} runs"
            raise PyRobotsError(msg)
        if not name.isidentifier():
            msg = f"an extension's name must be an identifier (robot.<name>), got {name!r}"
            raise PyRobotsError(msg)
        if self._name_taken(name) or name in self._attached:
            msg = f"cannot add the extension {name!r}: {type(self).__name__} already has that name"
            raise PyRobotsError(msg)
        self._extensions[name] = extension

    # -- from other threads -----------------------------------------------

    def call_soon_threadsafe(self, fn: Callable[..., object], *args: Any) -> None:
        """Call ``fn(*args)`` on the robot's loop, from any thread (e.g. a FastAPI ``def``).

        ``fn`` runs in the robot's root scope: an action it starts is a root action.

        Raises:
            RobotNotRunningError: The robot is not running.
        """
        self.executive.loop.call_soon_threadsafe(fn, *args)

    def run_threadsafe(self, coro: Coroutine[Any, Any, T]) -> concurrent.futures.Future[T]:
        """Run ``coro`` on the robot's loop from another thread; return a concurrent Future.

        ``asyncio.run_coroutine_threadsafe`` for this robot: block on
        ``.result(timeout)`` in a worker thread, or ``await
        asyncio.wrap_future(...)`` from another event loop.

        Raises:
            RobotNotRunningError: The robot is not running.
            EventLoopError: Called from the robot's own loop (it would deadlock:
                await the coroutine there instead).

        Examples:
            >>> import asyncio, threading
            >>> async def main() -> str:
            ...     async with Robot() as robot:
            ...         robot.state.mode = "idle"
            ...         async def set_mode() -> str:
            ...             robot.state.mode = "busy"
            ...             return robot.state.mode
            ...         out = []
            ...         worker = threading.Thread(
            ...             target=lambda: out.append(robot.run_threadsafe(set_mode()).result(5))
            ...         )
            ...         worker.start()
            ...         await asyncio.to_thread(worker.join)
            ...         return out[0]
            >>> asyncio.run(main())
            'busy'
        """
        loop = self.executive.loop
        if current_loop() is loop:
            coro.close()
            msg = (
                "run_threadsafe() is for other threads; on the robot's own loop, await the "
                "coroutine (or asyncio.create_task it)"
            )
            raise EventLoopError(msg)
        return asyncio.run_coroutine_threadsafe(coro, loop)

    # -- code that never awaits: the loop watchdog and to_thread -----------

    @property
    def block_threshold(self) -> float | None:
        """Seconds without the loop turning that the watchdog reports (None: no watchdog)."""
        return self._block_threshold

    def _watch_loop(self, loop: asyncio.AbstractEventLoop, threshold: float) -> None:
        executive = self.executive
        self._blockwatch = BlockWatch(
            loop,
            threshold,
            self._log_scope.logger("pyrobots_aio.watchdog"),
            self.instruments,
            lambda task: blocking_action(executive.running(), task),
        )
        self._blockwatch.start()

    def _unwatch_loop(self) -> None:
        watch, self._blockwatch = self._blockwatch, None
        if watch is not None:
            watch.stop()

    async def to_thread(self, fn: Callable[[*Ts], T], /, *args: *Ts) -> T:
        """Run blocking ``fn(*args)`` in a worker thread; return its result.

        For code that never awaits (a blocking driver call, a long computation),
        which on the loop would freeze every action, monitor and the simulation.
        It runs with a copy of the caller's context in one of the robot's own
        threads, started on demand and reused. Cancelling the caller (its
        action) stops the waiting at once; the call cannot be stopped (Python
        cannot stop a thread) and finishes in its thread, abandoned: its result
        is dropped, and an exception it raises then is logged with its
        traceback (logger ``pyrobots_aio.robot``).

        Up to ``min(32, os.cpu_count() + 4)`` calls (as many as asyncio's
        default executor runs) run at once for callers that still wait; further
        callers wait their turn. An abandoned call gives its turn up at once
        and runs on beside them, so a later call never waits behind it. Never
        more than 32 abandoned calls run: as any running call may yet be
        abandoned, fewer run at once as abandoned ones fill that room (one at
        a time beside 31), and while 32 run, a call is refused with
        `TooManyAbandonedCalls`, which counts them. The robot's exit waits for
        no call: it logs a WARNING naming the abandoned calls still running;
        each of their threads ends when its call returns, and no thread is left
        behind once they have. A call still blocked when the program ends holds
        the process until it returns (Python waits for its thread, as for any).

        In lockstep virtual time the call takes no simulated time: the clock
        stands still until it returns, as for ``loop.run_in_executor``, so a
        program sees the same ``robot.time()`` however long the thread runs;
        also after a cancel, until the abandoned call returns.

        Raises:
            EventLoopError: Called off the robot's loop.
            RobotNotRunningError: The robot is not running.
            TooManyAbandonedCalls: 32 abandoned calls still run (give the
                blocking calls a timeout so that they return).

        Examples:
            >>> import asyncio, time
            >>> async def main() -> float:
            ...     async with Robot() as robot:
            ...         return await robot.to_thread(lambda s: time.sleep(s) or s, 0.01)
            >>> asyncio.run(main())
            0.01
        """
        loop = self.executive.check_loop("call robot.to_thread")
        if self._workers is None:
            self._workers = Workers(self._log_scope.logger("pyrobots_aio.robot"))
        return await self._workers.run(loop, fn, *args)

    def _close_workers(self) -> None:
        workers, self._workers = self._workers, None
        if workers is not None:
            workers.close()

    # -- actions ----------------------------------------------------------

    async def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of the robot's clock (virtual time in lockstep simulation).

        Inside an action, time spent paused does not count: an action paused
        for 10 s in the middle of ``robot.sleep(2)`` wakes 12 s after it began.
        As ``asyncio.sleep``, 0 or less returns at once and ``math.inf`` never does.

        Raises:
            ValueError: ``seconds`` is NaN, or not a number a float can hold.
        """
        if seconds != math.inf:  # sleep(math.inf) sleeps until cancelled, as asyncio's does
            seconds = finite("seconds", seconds, must="a number of seconds (or math.inf)")
        handle = current_action.get()
        if handle is None or self.executive.get(handle.id) is not handle:  # not one of ours
            await asyncio.sleep(seconds)
            return
        loop = self.executive.loop
        start, frozen_before = loop.time(), handle.frozen_time()
        await asyncio.sleep(seconds)  # one timer, unless the action was frozen meanwhile
        while (frozen := handle.frozen_time() - frozen_before) > 0:
            deadline = start + seconds + frozen  # absolute: no float residue to sleep on
            if loop.time() >= deadline:
                return
            await sleep_until(deadline)

    def pause_all(self, reason: str | None = None) -> None:
        """Pause every running action (see `ActionHandle.pause`); `resume_all` thaws them.

        Raises:
            RobotNotRunningError: The robot is not running.
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(robot.pause_all, reason)``).
        """
        self.executive.check_loop("call robot.pause_all")
        self.executive.pause_all(reason)

    def resume_all(self) -> None:
        """Resume every paused action.

        Raises:
            RobotNotRunningError: The robot is not running.
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(robot.resume_all)``).
        """
        self.executive.check_loop("call robot.resume_all")
        self.executive.resume_all()

    def time(self) -> float:
        """The robot's clock: the running loop's time (simulation time in lockstep)."""
        return self.executive.loop.time()

    async def cancel_all(self, reason: str | None = None) -> None:
        """Cancel every running action and return once they are all done."""
        await self.executive.cancel_all(reason)

    async def cancel_all_others(self, reason: str | None = None) -> None:
        """Cancel every action except the calling one and its ancestors; wait for them."""
        me = current_action.get()
        await self.executive.cancel_all(reason, keep=() if me is None else (me,))

    def running(self) -> list[ActionInfo]:
        """Snapshots of every action not yet done, in start order.

        Cheap (about 0.6 µs an action): each snapshot's ``location`` is
        read from the action's coroutine only when asked.
        """
        snapshot = ActionInfo.of
        return [snapshot(h) for h in self.executive.running()]

    def actioninfo(self, ident: int) -> ActionInfo:
        """The snapshot of the running action with this id.

        Raises:
            ActionError: No running action has this id.
        """
        handle = self.executive.get(ident)
        if handle is None:
            running = [h.id for h in self.executive.running()]
            msg = f"no running action with id {ident!r}; running ids: {running[:20]}"
            raise ActionError(msg)
        return ActionInfo.of(handle)

    def action_tree(self) -> str:
        """The running actions as a printable tree (children indented under parents)."""
        return _render_tree(self.executive.roots())

    def handles(self) -> list[ActionHandle[Any]]:
        """The handles of every action not yet done, in start order."""
        return self.executive.running()

    # -- logging ----------------------------------------------------------

    def loglevel(self, level: int | str | None) -> None:
        """Set this robot's log level (``"DEBUG"``, ``logging.INFO`` ...); None: the loggers'.

        It applies to what the library logs about this robot only (its actions,
        monitors and resources): another robot in the same process is not
        affected, and no logger's level changes. Records at or above the level
        reach the handlers of the ``pyrobots_aio`` loggers (handlers are yours
        to add: the library never configures logging).

        Raises:
            ValueError: An unknown level.
        """
        self._log_scope.level = None if level is None else check_level(level)

    def debug(self) -> None:
        """Log everything the library says about this robot (``DEBUG``)."""
        self.loglevel(logging.DEBUG)

    def info(self) -> None:
        """Log the library's ``INFO`` messages and above about this robot."""
        self.loglevel(logging.INFO)

    def silent(self) -> None:
        """Log only what goes wrong with this robot: ``WARNING`` and above, as in pyRobots.

        ``INFO`` and ``DEBUG`` are dropped; warnings and errors stay (a missing
        ``await``, the loop watchdog's block reports, the emergency stop, a
        failing callback). ``loglevel(logging.CRITICAL + 1)`` drops everything.
        """
        self.loglevel(logging.WARNING)

    def __repr__(self) -> str:
        state = "running" if self.is_running else "stopped"
        return f"<{type(self).__name__} {state}{' dummy' if self.dummy else ''}>"


GenericRobot = Robot
"""pyRobots' name for the base robot class."""
