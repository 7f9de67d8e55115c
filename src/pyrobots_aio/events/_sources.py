"""What feeds a monitor's trigger: writes of a key, or evaluations of a predicate.

`KeySource` tests the condition synchronously on every write of its key
(`StateStore.subscribe`), so a pulse that lasts one write is seen; for
``increase=``/``decrease=`` each write first moves the ratcheting reference. A
`PredicateSource` evaluates the predicate inside `StateStore.track_reads` and
watches exactly the keys it read last time; a sync predicate is evaluated
inside the write, an async one in a task (re-evaluations that come while one
runs are coalesced into one more). ``poll`` adds a drift-free timer.
"""

from __future__ import annotations

import inspect
import logging
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable, Mapping

    from ..state import StateStore, Subscription
    from ._callbacks import CallbackRunner
    from ._conditions import Condition
    from ._trigger import Trigger

_log = logging.getLogger("pyrobots_aio.events")
_FAILED = object()  # the result of a predicate that raised


class _Failures:
    """Logs an evaluation error once, until an evaluation succeeds again."""

    __slots__ = ("_label", "failing")

    def __init__(self, label: str) -> None:
        self._label = label
        self.failing = False

    def failed(self, what: str) -> None:
        if not self.failing:
            self.failing = True
            _log.exception("%s: %s failed (logged once until it succeeds again)", self._label, what)

    def succeeded(self) -> None:
        self.failing = False


class KeySource:
    """Tests a key condition on every write of the key."""

    __slots__ = ("_failures", "_key", "_observed", "_ratchet", "_ref", "_sub", "_test", "_trigger")

    def __init__(
        self,
        store: StateStore,
        key: str,
        condition: Condition,
        trigger: Trigger,
        label: str,
    ) -> None:
        self._key = key
        self._test = condition.test()
        self._trigger = trigger
        self._ratchet = condition.ratchet()
        self._failures = _Failures(label)
        current = store[key]
        self._ref: Any = None  # the first reading that can serve sets it (in _holds)
        self._observed = False
        if condition.edge:
            trigger.prime(self._holds(current), current)
        self._sub: Subscription = store.subscribe(self._on_write, key)

    def rebase(self, value: Any) -> None:
        """Make ``value`` the reference of ``increase=``/``decrease=`` (at each firing)."""
        self._ref = value

    def observe_first(self, store: StateStore) -> None:
        """Observe the key's current value unless a write came first (a level that holds fires)."""
        if not self._observed:
            current = store[self._key]
            self._trigger.observe(self._holds(current), current)

    def stop(self) -> None:
        """Stop watching the key."""
        self._sub.close()

    def _on_write(self, changes: Mapping[str, Any]) -> None:
        value = changes[self._key]
        self._observed = True
        self._trigger.observe(self._holds(value), value)

    def _holds(self, value: Any) -> bool:
        try:
            if self._ratchet is not None:
                self._ref = self._ratchet(value, self._ref)
            holds = self._test(value, self._ref)
        except Exception:
            self._failures.failed(f"testing {value!r}")
            return False
        if self._failures.failing:
            self._failures.succeeded()
        return holds


class PredicateSource:
    """Evaluates a predicate when a key it read changes, and every ``poll`` seconds."""

    __slots__ = (
        "_anchor",
        "_dirty",
        "_failures",
        "_is_async",
        "_label",
        "_loop",
        "_poll",
        "_polls",
        "_predicate",
        "_reported",
        "_robot",
        "_runner",
        "_stopped",
        "_store",
        "_sub",
        "_task",
        "_timer",
        "_trigger",
        "_watched",
    )

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        store: StateStore,
        robot: object,
        predicate: Callable[[Any], object],
        *,
        trigger: Trigger,
        runner: CallbackRunner,
        poll: float | None,
        label: str,
    ) -> None:
        self._loop = loop
        self._store = store
        self._robot = robot
        self._predicate = predicate
        self._trigger = trigger
        self._runner = runner
        self._poll = poll
        self._label = label
        self._failures = _Failures(label)
        self._is_async = inspect.iscoroutinefunction(predicate) or inspect.iscoroutinefunction(
            type(predicate).__call__  # an object with an async __call__
        )
        self._sub: Subscription | None = None
        self._watched: frozenset[str] = frozenset()
        self._task: asyncio.Task[None] | None = None
        self._dirty = False
        self._stopped = False
        self._timer: asyncio.TimerHandle | None = None
        self._anchor = loop.time()
        self._polls = 0
        self._reported = False

    def start(self) -> None:
        """Evaluate for the first time and start watching.

        A sync predicate is evaluated now, and what it raises propagates; its
        result is observed at the next loop iteration, once ``do()`` has run.
        An async predicate's first evaluation starts in a task. A predicate
        that read no state key and has no ``poll`` is warned about (an async
        one after its first evaluation): nothing would evaluate it again.
        """
        if self._is_async:
            self._evaluate()
        else:
            result = self._call()
            self._loop.call_soon(self._observe_first, result)
            self._warn_if_deaf()
        if self._poll is not None:
            self._schedule_poll()

    def stop(self) -> None:
        """Stop watching, polling and evaluating."""
        self._stopped = True
        if self._sub is not None:
            self._sub.close()
        if self._timer is not None:
            self._timer.cancel()
        if self._task is not None:
            self._task.cancel("the monitor stopped")

    # -- evaluating -------------------------------------------------------------

    def _call(self) -> object:
        with self._store.track_reads() as reads:
            try:
                return self._predicate(self._robot)
            finally:
                self._watch(frozenset(reads))

    def _observe_first(self, result: object) -> None:
        if not self._stopped and not self._reported:
            self._report(result)

    def _evaluate(self) -> None:
        if self._is_async:
            if self._task is None:
                self._task = self._runner.track(self._evaluate_async())
            else:
                self._dirty = True
            return
        try:
            result = self._call()
        except Exception:
            self._failures.failed("the predicate")
            result = _FAILED
        self._report(result)

    async def _evaluate_async(self) -> None:
        try:
            while True:
                self._dirty = False
                before = self._store.version()
                with self._store.track_reads() as reads:
                    try:
                        result = await self._predicate(self._robot)  # type: ignore[misc]
                    except Exception:
                        self._failures.failed("the predicate")
                        result = _FAILED
                    finally:
                        newly_read = reads - self._watched
                        self._watch(frozenset(reads))
                if newly_read and self._store.version() != before:
                    self._dirty = True  # a key not watched yet may have changed meanwhile
                first = not self._reported
                self._report(result)
                if first:
                    self._warn_if_deaf()
                if not self._dirty or self._stopped:
                    break
        finally:
            self._task = None

    def _report(self, result: object) -> None:
        self._reported = True
        if result is _FAILED:  # already logged; it does not hold
            self._trigger.observe(False, None)
            return
        try:
            holds = bool(result)
        except Exception:
            self._failures.failed(f"bool() of its result {result!r}")
            holds = False
        else:
            self._failures.succeeded()
        self._trigger.observe(holds, result)

    def _warn_if_deaf(self) -> None:
        if not self._watched and self._poll is None and not self._stopped:
            _log.warning(
                "%s: the predicate read no state key and has no poll=; it will not be "
                "evaluated again (read robot.state, or give poll=SECONDS)",
                self._label,
            )

    # -- watching ------------------------------------------------------------------

    def _watch(self, keys: frozenset[str]) -> None:
        if keys == self._watched or self._stopped:
            return
        if self._sub is not None:
            self._sub.close()
            self._sub = None
        self._watched = keys
        if keys:
            self._sub = self._store.subscribe(self._on_write, keys)

    def _on_write(self, _changes: Mapping[str, Any]) -> None:
        self._evaluate()

    def _schedule_poll(self) -> None:
        assert self._poll is not None
        self._polls += 1
        at = self._anchor + self._polls * self._poll
        self._timer = self._loop.call_at(at, self._on_poll)

    def _on_poll(self) -> None:
        self._schedule_poll()  # before evaluating: a one-shot that fires cancels it
        self._evaluate()
