"""A virtual-time asyncio event loop: the clock advances only when the loop is idle.

``loop.time()`` starts at 0.0. Whenever the loop has nothing ready to run and
no I/O is pending, it jumps straight to its next timer instead of sleeping, so
``await asyncio.sleep(3600)`` returns at once with ``loop.time() == 3600.0``,
and ``asyncio.timeout``, ``call_later``/``call_at`` and ``wait_for`` all fire
in virtual time, deterministically, in the order real time would give.
Virtual time lands exactly on each timer's own ``when``, so a periodic
``call_at(start + n * period)`` never drifts.

The loop still blocks for real when it must wait for something outside virtual
time:

- no timer is scheduled at all, or only at infinity (``anyio.sleep_forever``):
  only I/O or ``call_soon_threadsafe`` can wake it;
- work handed to an executor (``run_in_executor``, ``asyncio.to_thread``,
  ``getaddrinfo``) is pending: such work takes no virtual time, so the same
  program always sees the same ``loop.time()`` however long the thread runs.
  A thread that itself waits for one of the loop's timers would wait forever;
  threads started by other means (``anyio.to_thread``) are not counted and
  race virtual time.

A loop that never waits never lets virtual time move: a task polling with
``await asyncio.sleep(0)`` would freeze every timer, timeouts and the cancel
watchdog included (a livelock real time does not have). So after `BUSY_LIMIT`
iterations in a row without waiting, the loop says so once (a warning) and
lets each further busy iteration take virtual time up to the next timer, as
if the busy work took that long, until it waits again. This depends only on
iteration counts, so it stays deterministic.

Entry points: `run_lockstep` (like ``asyncio.run``/``anyio.run``), `new_virtual_loop`
(a ``loop_factory`` for ``asyncio.Runner``, ``anyio.run`` backend options and
pytest-asyncio's ``pytest_asyncio_loop_factories`` hook) and
`VirtualTimePolicy` for code that still configures loops through policies.
"""

from __future__ import annotations

import asyncio
import logging
import math
import selectors
import sys
import warnings
from typing import TYPE_CHECKING, Any, TypeVar, TypeVarTuple

from .._core._numbers import finite
from .._exceptions import EventLoopError
from ._closing import SignalSafeLoop

if TYPE_CHECKING:
    from collections import deque
    from collections.abc import Callable, Coroutine, Mapping
    from concurrent.futures import Executor

    from _typeshed import FileDescriptorLike

_T = TypeVar("_T")
_Ts = TypeVarTuple("_Ts")

_SelectResult = list[tuple[selectors.SelectorKey, int]]
_log = logging.getLogger("pyrobots_aio.clock")

BUSY_LIMIT = 100_000
"""Iterations in a row without waiting after which virtual time moves anyway (see above)."""


class _IdleSkippingSelector(selectors.BaseSelector):
    """Wraps a real selector; where the loop would sleep, it advances virtual time."""

    def __init__(self, inner: selectors.BaseSelector, loop: VirtualTimeLoop) -> None:
        self._inner = inner
        self._loop = loop

    def select(self, timeout: float | None = None) -> _SelectResult:
        ready = self._inner.select(0)
        if ready:
            return ready
        loop = self._loop
        if timeout is not None and timeout <= 0:  # callbacks are ready: a busy iteration
            loop._busy_iteration()
            return ready
        loop._busy = 0
        if timeout is not None and loop._skip_to_next_timer():
            return []
        return self._inner.select(None)

    def register(
        self, fileobj: FileDescriptorLike, events: int, data: Any = None
    ) -> selectors.SelectorKey:
        return self._inner.register(fileobj, events, data)

    def unregister(self, fileobj: FileDescriptorLike) -> selectors.SelectorKey:
        return self._inner.unregister(fileobj)

    def modify(
        self, fileobj: FileDescriptorLike, events: int, data: Any = None
    ) -> selectors.SelectorKey:
        return self._inner.modify(fileobj, events, data)

    def get_map(self) -> Mapping[FileDescriptorLike, selectors.SelectorKey]:
        return self._inner.get_map()

    def close(self) -> None:
        self._inner.close()


class VirtualTimeLoop(SignalSafeLoop):
    """An asyncio selector event loop whose clock is virtual.

    ``time()`` starts at 0.0 and only moves when the loop would otherwise wait:
    then it jumps to the next timer's due time. Not thread-safe beyond what
    asyncio guarantees (``call_soon_threadsafe`` works as usual).

    Examples:
        >>> import asyncio
        >>> async def main() -> float:
        ...     await asyncio.sleep(3600)
        ...     return asyncio.get_running_loop().time()
        >>> with asyncio.Runner(loop_factory=VirtualTimeLoop) as runner:
        ...     runner.run(main())
        3600.0
    """

    def __init__(self) -> None:
        self._now = 0.0
        self._thread_jobs = 0
        self._busy = 0
        self._busy_warned = False
        super().__init__(_IdleSkippingSelector(selectors.DefaultSelector(), self))

    def time(self) -> float:
        """Return the virtual time in seconds (0.0 when the loop was created)."""
        return self._now

    def run_in_executor(
        self,
        executor: Executor | None,
        func: Callable[[*_Ts], _T],
        *args: *_Ts,
    ) -> asyncio.Future[_T]:
        """Run ``func(*args)`` in an executor; virtual time stands still until it is done."""
        future = super().run_in_executor(executor, func, *args)
        self._thread_jobs += 1
        future.add_done_callback(self._thread_job_done)
        return future

    if sys.version_info >= (3, 12):
        # The signature is the stdlib's, timeout parameter included.
        async def shutdown_default_executor(self, timeout: float | None = None) -> None:  # noqa: ASYNC109
            """Shut the default executor down; its join takes no virtual time."""
            self._thread_jobs += 1
            try:
                await super().shutdown_default_executor(timeout)
            finally:
                self._thread_jobs -= 1

    else:

        async def shutdown_default_executor(self) -> None:
            """Shut the default executor down; its join takes no virtual time."""
            self._thread_jobs += 1
            try:
                await super().shutdown_default_executor()
            finally:
                self._thread_jobs -= 1

    def pending_timers(self) -> list[asyncio.TimerHandle]:
        """Return the timers still to fire, earliest first (cancelled ones left out).

        What the loop will wake up for if nothing else happens: a program that
        costs no CPU while idle leaves none behind.

        Examples:
            >>> async def main() -> list[float]:
            ...     loop = asyncio.get_running_loop()
            ...     loop.call_later(2.0, lambda: None)
            ...     loop.call_later(1.0, lambda: None).cancel()
            ...     return [timer.when() for timer in loop.pending_timers()]
            >>> run_lockstep(main)
            [2.0]
        """
        scheduled: list[asyncio.TimerHandle] = self._scheduled  # type: ignore[attr-defined]
        return sorted(timer for timer in scheduled if not timer.cancelled())  # by when()

    def ready_callbacks(self) -> list[asyncio.Handle]:
        """Return the callbacks queued to run at the next iteration (cancelled ones left out).

        Examples:
            >>> async def main() -> int:
            ...     loop = asyncio.get_running_loop()
            ...     loop.call_soon(lambda: None)
            ...     loop.call_soon(lambda: None).cancel()
            ...     return len(loop.ready_callbacks())
            >>> run_lockstep(main)
            1
        """
        ready: deque[asyncio.Handle] = self._ready  # type: ignore[attr-defined]
        return [handle for handle in ready if not handle.cancelled()]

    def skip_ahead(self, when: float) -> bool:
        """Move virtual time on to ``when`` now if nothing would run before; tell whether it did.

        For a callback that would only schedule itself again at ``when`` (the
        simulator's control tick) and can go on at once instead: True if no
        callback is ready, no timer is due at or before ``when``, no thread job
        runs and the loop is not stopping. The loop's turn in between would have
        done nothing but poll I/O (the caller must let it turn now and then).

        Examples:
            >>> async def main() -> tuple[bool, float, bool]:
            ...     loop = asyncio.get_running_loop()
            ...     skipped = loop.skip_ahead(1.0)  # nothing else to do before t = 1
            ...     now = loop.time()
            ...     loop.call_later(0.5, lambda: None)
            ...     return skipped, now, loop.skip_ahead(2.0)  # a timer falls due first
            >>> run_lockstep(main)
            (True, 1.0, False)

        Raises:
            ValueError: ``when`` is not a finite number (the clock is left as it was).
        """
        if type(when) is not float or when - when != 0.0:  # (floats pass at once: every tick)
            when = finite("when", when, fix="pass the loop time of the next tick")
        if self._ready or self._thread_jobs or self._stopping:  # type: ignore[attr-defined]
            return False
        scheduled: list[asyncio.TimerHandle] = self._scheduled  # type: ignore[attr-defined]
        # (the first timer's when(), without the call: at every tick)
        if scheduled and scheduled[0]._when <= when:  # type: ignore[attr-defined]
            return False
        self._now = max(self._now, when)
        return True

    def _thread_job_done(self, _future: asyncio.Future[Any]) -> None:
        self._thread_jobs -= 1

    def _busy_iteration(self) -> None:
        """Count an iteration that did not wait; past `BUSY_LIMIT`, let it take virtual time."""
        self._busy += 1
        if self._busy < BUSY_LIMIT:
            return
        if not self._busy_warned:
            self._busy_warned = True
            _log.warning(
                "virtual time: the event loop ran %d iterations in a row without waiting (a "
                "task polling with 'await asyncio.sleep(0)'?); from now on, while it stays "
                "busy, each iteration lets virtual time reach the next timer",
                BUSY_LIMIT,
            )
        self._skip_to_next_timer()

    def _skip_to_next_timer(self) -> bool:
        """Advance virtual time to the earliest timer; False if the loop must wait for real."""
        if self._thread_jobs:
            return False
        # BaseEventLoop keeps its timers in the heap ``_scheduled`` (as it has since 3.4);
        # landing on the head's own ``when`` keeps periodic timers free of drift.
        scheduled: list[asyncio.TimerHandle] = self._scheduled  # type: ignore[attr-defined]
        if not scheduled or scheduled[0].when() == math.inf:  # sleep(inf) never wakes up
            return False
        self._now = max(self._now, scheduled[0].when())
        return True


def new_virtual_loop() -> VirtualTimeLoop:
    """Create a new `VirtualTimeLoop`: a ``loop_factory`` for runners and test plugins.

    Examples:
        >>> import anyio
        >>> async def now() -> float:
        ...     await anyio.sleep(2.5)
        ...     return anyio.current_time()
        >>> anyio.run(now, backend_options={"loop_factory": new_virtual_loop})
        2.5
    """
    return VirtualTimeLoop()


with warnings.catch_warnings():
    # Python 3.14 deprecates event loop policies; importing this module stays silent.
    warnings.simplefilter("ignore", DeprecationWarning)

    class VirtualTimePolicy(asyncio.DefaultEventLoopPolicy):
        """An event loop policy whose new loops are `VirtualTimeLoop`s.

        Prefer `run_lockstep` or a ``loop_factory`` (`new_virtual_loop`); policies are
        deprecated from Python 3.14 on.
        """

        def new_event_loop(self) -> VirtualTimeLoop:
            """Create a new `VirtualTimeLoop`."""
            return new_virtual_loop()


def run_lockstep(main: Callable[[*_Ts], Coroutine[Any, Any, _T]], *args: *_Ts) -> _T:
    """Run ``main(*args)`` on a fresh virtual-time loop and return its result.

    Like ``asyncio.run``/``anyio.run``: remaining tasks are cancelled, async
    generators and the default executor are shut down and the loop is closed,
    whatever the outcome; an exception of ``main`` propagates.

    Args:
        main: The coroutine function to run.
        *args: Its positional arguments.

    Returns:
        What ``main`` returned.

    Raises:
        EventLoopError: An event loop is already running in this thread (a
            ``RuntimeError``); the message says to use ``asyncio.to_thread``.

    Examples:
        >>> import asyncio
        >>> async def later(delay: float) -> float:
        ...     await asyncio.sleep(delay)
        ...     return asyncio.get_running_loop().time()
        >>> run_lockstep(later, 60)
        60.0
    """
    if asyncio._get_running_loop() is None:  # not inside an except clause: no stray context
        with asyncio.Runner(loop_factory=new_virtual_loop) as runner:
            return runner.run(main(*args))
    name = getattr(main, "__name__", repr(main))
    msg = (
        f"pyrobots_aio.sim.run({name}) cannot run inside a running event loop: it runs "
        f"{name} on a virtual-time loop of its own; from async code, run it in a thread: "
        f"await asyncio.to_thread(pyrobots_aio.sim.run, {name})"
    )
    raise EventLoopError(msg)


def is_virtual(loop: asyncio.AbstractEventLoop | None = None) -> bool:
    """Tell whether ``loop`` (default: the running loop) runs in virtual time.

    Raises:
        RuntimeError: ``loop`` is None and no event loop is running.
    """
    if loop is None:
        loop = asyncio.get_running_loop()
    return isinstance(loop, VirtualTimeLoop)
