"""One rclpy context, node and executor, spinning on a thread of their own.

rclpy 9 has no asyncio executor, so the bridge runs rclpy's
``SingleThreadedExecutor`` on a dedicated thread and hands everything that
arrives there (service responses, goal results, graph events) to the event
loop with ``loop.call_soon_threadsafe``: the loop never polls and never
blocks on rclpy. The bridge's subscriptions are the exception: the node's
`Receiver` takes their messages on a thread of its own, cheaper per message
than the executor (see `_receiver`).

The thread creates the context and node itself (a DDS participant takes
tens of milliseconds to come up) and tears them down when the executor
stops, so `RosThread.stop` leaves no thread, node or context behind.

Each node has its own context (never rclpy's global default one): two robots
in one process, or two tests in a row, share nothing, and neither installs
rclpy's signal handlers.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import threading
from typing import TYPE_CHECKING, Any

from .._exceptions import Ros2Error
from ._rclpy import rclpy_module
from ._receiver import Receiver

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

_log = logging.getLogger("pyrobots_aio.ros2")

RECHECK_PERIOD = 0.05
"""Seconds between two looks at the ROS graph while something waits for a server.

rclpy tells nobody when a service or action server appears (its own
``wait_for_service`` sleeps and looks again), so the ROS thread looks on a
steady-clock timer, only while a call or a goal waits for its server.
"""

SPIN_BOUND = 0.5
"""Seconds the ROS thread waits in one spin at most before it looks whether to stop.

`RosThread.stop` wakes the executor (``executor.shutdown``), but on a loaded
machine that wake-up was once lost: the thread slept on in its wait set, and
the robot's exit waited for it forever. Looking again this often bounds the
exit; a node with nothing to do then only goes back to its wait. The bound is
a timer of the node's own, made once: a timeout given to ``spin_once`` would
make rclpy build a timer at every wake-up, one per message received.
"""
JOIN_BOUND = 5.0
"""Seconds the loop waits for the ROS thread to end once its exit was cancelled."""


DISCOVERY_RANGE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
QUIET_RCL_LOGGING = ("--disable-stdout-logs", "--disable-external-lib-logs")
"""rcl's own console and log-file output, off: Python's logging reports, and /rosout carries."""
_environment = threading.Lock()


@contextlib.contextmanager
def localhost_discovery_by_default() -> Iterator[None]:
    """Discovery on this machine only, unless the environment says otherwise (DESIGN §12).

    ROS 2 discovers across the subnet when ``ROS_AUTOMATIC_DISCOVERY_RANGE``
    is unset: its multicast reaches the machine's network interface. rcl
    reads the range when a context starts, and rclpy passes it nothing else,
    so the variable is set to ``LOCALHOST`` for that moment only, when
    neither it nor the older ``ROS_LOCALHOST_ONLY`` is set.
    """
    with _environment:
        if DISCOVERY_RANGE in os.environ or "ROS_LOCALHOST_ONLY" in os.environ:
            yield
            return
        os.environ[DISCOVERY_RANGE] = "LOCALHOST"
        try:
            yield
        finally:
            del os.environ[DISCOVERY_RANGE]


@contextlib.contextmanager
def _rejected_arguments(ros_args: list[str]) -> Iterator[None]:
    """Turn rclpy's refusal of ROS arguments into a `Ros2Error` quoting them and rcl's reason."""
    errors = rclpy_module("rclpy.impl.implementation_singleton").rclpy_implementation
    try:
        yield
    except errors.UnknownROSArgsError as err:
        msg = f"unknown ROS arguments {err} in --ros-args {' '.join(ros_args)}"
        raise Ros2Error(msg) from err
    except errors.RCLError as err:
        reason = str(err).split(", at ")[0]
        if not ros_args or "pars" not in reason:
            raise
        msg = f"ROS 2 rejects --ros-args {' '.join(ros_args)}: {reason}"
        raise Ros2Error(msg) from err


def _settle(
    future: asyncio.Future[Any], result: Any = None, error: BaseException | None = None
) -> None:
    if future.done():
        return
    if error is not None:
        future.set_exception(error)
    else:
        future.set_result(result)


def _nothing() -> None:
    """The SPIN_BOUND timer's callback: its firing alone ends the executor's wait."""


def _steady_clock() -> Any:
    clock = rclpy_module("rclpy.clock")
    return clock.Clock(clock_type=clock.ClockType.STEADY_TIME)


def _fail_quietly(future: asyncio.Future[Any], error: BaseException) -> None:
    """Fail ``future``; whoever awaits it gets ``error``, and nobody is told if nobody does."""
    if not future.done():
        future.set_exception(error)
        future.exception()  # retrieved: a future nobody awaits any more is not reported


class RosThread:
    """An rclpy node spinning on its own thread, handing its work to the event loop.

    Args:
        name: The node's name (already validated).
        namespace: Its absolute namespace (already validated).
        domain_id: The DDS domain; None reads ``ROS_DOMAIN_ID`` (0 if unset).
        use_sim_time: Whether the node's clock follows ``/clock`` (None: as its
            ROS arguments say, ``-p use_sim_time:=true``; else not).
        ros_args: Extra ROS arguments for the node (``["-r", "from:=to"]`` ...).
        citizen: A node of its own process (``sim-node``): it logs to
            ``/rosout`` and serves its parameters, its ROS arguments are the
            process's too (``--log-level`` ...), and rcl logs neither to the
            console nor to files (Python's logging does).
    """

    def __init__(
        self,
        name: str,
        namespace: str,
        *,
        domain_id: int | None,
        use_sim_time: bool | None,
        ros_args: list[str],
        citizen: bool = False,
    ) -> None:
        self.name, self.namespace = name, namespace
        self.domain_id = domain_id
        self.use_sim_time = use_sim_time
        self.ros_args = ros_args
        self.citizen = citizen
        self.node: Any = None
        self.receiver: Any = None  # the Receiver of the node's subscriptions, made with it
        self._context: Any = None
        self._executor: Any = None
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stopped: asyncio.Future[None] | None = None
        self._pending: set[asyncio.Future[Any]] = set()
        self._waiters: list[tuple[Callable[[], bool], asyncio.Future[None]]] = []
        self._lock = threading.Lock()  # guards the waiters, the recheck timer and stopping
        self._stopping = False
        self._recheck: Any = None

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        """The event loop the ROS thread hands its work to."""
        if self._loop is None:
            msg = "the ROS 2 node is not running; use it inside 'async with robot:'"
            raise Ros2Error(msg)
        return self._loop

    # -- lifecycle ----------------------------------------------------------------

    async def start(self) -> None:
        """Create the context and node on a new thread and start spinning; return once up."""
        rclpy_module()  # fail here, on the loop, if rclpy is missing
        loop = self._loop = asyncio.get_running_loop()
        ready: asyncio.Future[None] = loop.create_future()
        self._stopped = loop.create_future()
        self._thread = threading.Thread(
            target=self._run, args=(ready,), name=f"pyrobots_aio.ros2 {self.name}", daemon=True
        )
        self._thread.start()
        try:
            await asyncio.shield(ready)
        except asyncio.CancelledError:
            await self.stop()
            raise
        except BaseException:
            await self._joined()
            raise

    async def stop(self) -> None:
        """Stop spinning, destroy the node and context, end the thread; fail what still waits."""
        if self._thread is None:
            return
        with self._lock:
            self._stopping = True
            executor = self._executor
        if executor is not None:  # else the thread sees `_stopping` before it spins
            executor.shutdown(timeout_sec=0)
        await self._joined()
        error = Ros2Error(f"the ROS 2 node {self.name!r} stopped")
        for future in list(self._pending):
            _fail_quietly(future, error)
        with self._lock:
            waiters, self._waiters = self._waiters, []
        for _, waiter in waiters:
            _fail_quietly(waiter, error)

    async def _joined(self) -> None:
        """Wait for the thread to finish its teardown (shielded: it is quick and must end)."""
        thread, stopped = self._thread, self._stopped
        if thread is None or stopped is None:
            return
        try:
            await asyncio.shield(stopped)
        finally:  # cancelled meanwhile: the thread is told to stop, and ends within SPIN_BOUND
            thread.join(JOIN_BOUND)
            if thread.is_alive():
                _log.error(
                    "the ROS 2 thread of node %s did not end within %s s", self.name, JOIN_BOUND
                )
            self._thread = None

    def _run(self, ready: asyncio.Future[None]) -> None:
        try:
            executor = self._create()
        except BaseException as exc:  # handed to start(), which raises it
            self._destroy()
            self.to_loop(_settle, ready, None, exc)
            self.to_loop(_settle, self._stopped, None)
            return
        with self._lock:
            stopping = self._stopping
            self._executor = executor
        self.to_loop(_settle, ready, None)
        try:
            if not stopping:
                self._spin(executor)
        finally:
            self._destroy()
            self.to_loop(_settle, self._stopped, None)

    def _spin(self, executor: Any) -> None:
        """``executor.spin()``, except that a callback that raises does not stop the node."""
        # As rclpy's spin() loops, and our own stop flag besides (see SPIN_BOUND).
        self.node.create_timer(SPIN_BOUND, _nothing, clock=_steady_clock())
        while not self._stopping and executor.context.ok() and not executor._is_shutdown:
            try:
                executor.spin_once()
            except Exception:  # rclpy re-raises a callback's error here: log it, go on
                _log.exception("a ROS 2 callback of node %s failed", self.name)

    def _create(self) -> Any:
        rclpy_node = rclpy_module("rclpy.node")
        executors = rclpy_module("rclpy.executors")
        parameter = rclpy_module("rclpy.parameter")
        context = self._context = rclpy_module("rclpy.context").Context()
        ros_args = ["--ros-args", *self.ros_args] if self.ros_args else None
        # A library node sets no process-wide logging up (rcl would write log files under
        # ~/.ros); a citizen's rosout needs it, without rcl's console and file output.
        overrides = (
            []
            if self.use_sim_time is None
            else [parameter.Parameter("use_sim_time", value=self.use_sim_time)]
        )
        with localhost_discovery_by_default(), _rejected_arguments(self.ros_args):
            context.init(
                args=[*(ros_args or ["--ros-args"]), *QUIET_RCL_LOGGING] if self.citizen else [],
                domain_id=self.domain_id,
                initialize_logging=self.citizen,
            )
            self.node = rclpy_node.Node(
                self.name,
                namespace=self.namespace,
                context=context,
                cli_args=ros_args,
                use_global_arguments=False,
                enable_rosout=self.citizen,
                start_parameter_services=self.citizen,
                parameter_overrides=overrides,
            )
        self.receiver = Receiver(self.name, context, SPIN_BOUND)
        executor = executors.SingleThreadedExecutor(context=context)
        executor.add_node(self.node)
        return executor

    def _destroy(self) -> None:
        with self._lock:
            executor, self._executor = self._executor, None
        if executor is not None:
            executor.shutdown(timeout_sec=0)
        if self.receiver is not None:
            self.receiver.stop(JOIN_BOUND)
        if self.node is not None:
            self.node.destroy_node()
        if self._context is not None:
            self._context.try_shutdown()
        self.node = self._context = self._recheck = self.receiver = None

    # -- handing work over --------------------------------------------------------

    def to_loop(self, fn: Callable[..., object], *args: object) -> None:
        """From the ROS thread: run ``fn(*args)`` on the event loop, soon."""
        loop = self._loop
        if loop is None:
            return
        try:
            loop.call_soon_threadsafe(fn, *args)
        except RuntimeError:  # the loop is closed: nobody is left to tell
            _log.debug("dropped %r: the event loop is closed", fn)

    def wrap(self, rclpy_future: Any) -> asyncio.Future[Any]:
        """An asyncio future settled, on the loop, with what ``rclpy_future`` settles with."""
        future: asyncio.Future[Any] = self.loop.create_future()
        self._pending.add(future)
        future.add_done_callback(self._pending.discard)

        def done(settled: Any) -> None:  # on the ROS thread (or here, if already done)
            error = settled.exception()
            self.to_loop(_settle, future, None if error else settled.result(), error)

        rclpy_future.add_done_callback(done)
        return future

    async def wait_until(self, ready: Callable[[], bool]) -> None:
        """Return once ``ready()`` (a look at the ROS graph) holds; re-checked on the ROS thread."""
        if ready():
            return
        future: asyncio.Future[None] = self.loop.create_future()
        with self._lock:
            self._waiters.append((ready, future))
            if self._recheck is None:
                self._recheck = self.node.create_timer(
                    RECHECK_PERIOD, self._check, clock=_steady_clock()
                )
            else:
                self._recheck.reset()
        try:
            await future
        finally:
            with self._lock:
                self._waiters = [(r, f) for r, f in self._waiters if f is not future]

    def _check(self) -> None:  # on the ROS thread, from the timer
        with self._lock:
            waiters = list(self._waiters)
        settled: dict[asyncio.Future[None], BaseException | None] = {}
        for ready, future in waiters:
            try:
                if ready():
                    settled[future] = None
            except Exception as exc:  # handed to the waiter
                settled[future] = exc
        with self._lock:  # decided under the lock: a waiter added meanwhile restarts the timer
            self._waiters = [(r, f) for r, f in self._waiters if f not in settled]
            if not self._waiters and self._recheck is not None:
                self._recheck.cancel()
        for future, error in settled.items():
            self.to_loop(_settle, future, None, error)
