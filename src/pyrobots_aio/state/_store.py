"""The robot's state: named values with timestamps, versions and lossless change notification.

Backends write it every control tick and users may too; event monitors must
see every write, so subscribers are called synchronously inside the write, with
the values written (`_notify`). Reads can be tracked to learn which keys a
predicate depends on (`_reads`).

The store is not thread-safe: write it from the event loop's thread (a backend
that samples in a thread hands its readings over with ``call_soon_threadsafe``).
A running robot's store refuses writes from other threads (`StateStore.bind`).
"""

from __future__ import annotations

import asyncio
import difflib
import reprlib
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from threading import get_ident
from typing import TYPE_CHECKING, Any

from pyrobots_aio._core._loops import clock_of, running_here, wrong_loop
from pyrobots_aio._exceptions import UnknownStateKeyError

from ._filter import MovingAverage
from ._ledger import WriteLedger
from ._notify import SubscriberIndex, Subscription, check_key
from ._reads import READS, tracking

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator
    from collections.abc import Set as AbstractSet
    from contextlib import AbstractContextManager

_SHOWN_KEYS = 8  # keys listed in an unknown-key message; the others are counted
_repr = reprlib.Repr()
_repr.maxdict = 4


@dataclass(frozen=True, slots=True)
class StateSample:
    """One key's latest write.

    Attributes:
        value: The value written.
        timestamp: When it was written, on the store's clock (the loop's ``time()``).
        version: How many times the key has been written (1 after the first write).
    """

    value: Any
    timestamp: float
    version: int


def _loop_time() -> float:
    try:
        return asyncio.get_running_loop().time()
    except RuntimeError:
        # No loop runs (state filled before asyncio.run): asyncio's loops use this clock.
        return time.monotonic()


class StateStore(Mapping[str, Any]):
    """The robot's named values (``robot.state``), with timestamps, versions and notification.

    A ``Mapping[str, Any]`` with attribute access (``store.bumper``), written
    with `set`, `update`, ``store[k] = v`` or ``store.k = v``. Keys are never
    deleted (write None instead).

    Attribute access reaches a key only when the name does not start with
    ``_`` and is not an attribute of the store itself: a key named ``update``
    or ``keys`` is read as ``store["update"]``, and ``store.update = 1`` raises.

    Every write stamps the key with the store's clock (default: the running
    loop's ``time()``, so virtual time in simulation), bumps the key's version
    and the store's version, then calls the key's subscribers synchronously
    with ``{key: value}``; `update` writes a batch as one write. Writes made
    by a subscriber are notified once the current notification is over, so
    every subscriber sees the writes in the order they happened. Writing the
    value a key already has is a write like any other (stamped, counted,
    notified): a level condition with ``max_firing_freq=0`` fires on each
    write that finds it true, and a recorder samples a value that held still.

    Not thread-safe: write it from the event loop's thread.

    Examples:
        >>> store = StateStore(clock=lambda: 0.0)
        >>> seen = []
        >>> sub = store.subscribe(lambda changes: seen.append(dict(changes)), keys="bumper")
        >>> store.bumper = True
        >>> store.update(bumper=False, docked=True)
        >>> seen, store.bumper, store.version("bumper")
        ([{'bumper': True}, {'bumper': False}], False, 2)
    """

    __slots__ = (
        "_clock",
        "_given_clock",
        "_ident",
        "_ledger",
        "_loop",
        "_subscribers",
        "_thread",
        "_values",
        "_windows",
    )

    def __init__(
        self,
        initial: Mapping[str, Any] | None = None,
        *,
        clock: Callable[[], float] | None = None,
    ) -> None:
        """Create a store, optionally with initial values (written as one batch).

        Args:
            initial: Values to write at once.
            clock: Where timestamps come from; default: the running loop's
                ``time()``, or ``time.monotonic()`` while no loop runs.
        """
        self._given_clock = clock
        self._clock = clock or _loop_time
        self._values: dict[str, Any] = {}
        self._ledger = WriteLedger()  # (it counts the writes: the store's version)
        self._subscribers = SubscriberIndex()
        self._windows: dict[str, MovingAverage] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread = ""
        self._ident = 0
        if initial:
            self.update(initial)

    def bind(self, loop: asyncio.AbstractEventLoop | None) -> None:
        """Accept writes only from ``loop`` (its thread) from now on; None: from anywhere.

        A running robot binds its store to its loop: a write from a worker
        thread then raises `EventLoopError` naming the thread-safe way in
        (``robot.call_soon_threadsafe``), instead of racing the loop.
        """
        self._loop = loop
        self._thread = threading.current_thread().name if loop is not None else ""
        self._ident = threading.get_ident()
        if self._given_clock is None:  # a bound store reads its loop's clock directly
            self._clock = _loop_time if loop is None else clock_of(loop)

    # -- reading --------------------------------------------------------------

    def __getitem__(self, key: str) -> Any:
        log = READS.get()
        if log is not None:
            log.record(self, key)
        try:
            return self._values[key]
        except KeyError:
            raise self._unknown(key) from None

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        return self[name]

    def __contains__(self, key: object) -> bool:
        log = READS.get()
        if log is not None and isinstance(key, str):
            log.record(self, key)
        return key in self._values

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def get(self, key: str, default: Any = None) -> Any:
        """Return the value of ``key``, or ``default`` if it was never written."""
        log = READS.get()
        if log is not None:
            log.record(self, key)
        return self._values.get(key, default)

    def sample(self, key: str) -> StateSample:
        """Return the value of ``key`` with its timestamp and version."""
        value = self[key]
        return StateSample(value, self._ledger.stamp(key), self._ledger.version(key))

    def timestamp(self, key: str) -> float:
        """Return when ``key`` was last written, on the store's clock."""
        # Recorders ask on every write of the keys they sample: no StateSample, no helper.
        log = READS.get()
        if log is not None:
            log.record(self, key)
        try:
            return self._ledger.stamp(key)
        except KeyError:
            raise self._unknown(key) from None

    def version(self, key: str | None = None) -> int:
        """Return how many times ``key`` was written, or the store's version when None.

        The store's version counts write operations: a batch `update` is one.
        """
        if key is None:
            return self._ledger.writes
        return self.sample(key).version

    def require(self, *keys: str) -> None:
        """Raise `UnknownStateKeyError`, closest keys in the message, for the first missing key.

        Not recorded by `track_reads`.
        """
        for key in keys:
            if key not in self._values:
                raise self._unknown(key)

    def track_reads(self) -> AbstractContextManager[AbstractSet[str]]:
        """Record the keys read from this store inside the ``with`` block (this task only).

        Item, attribute, `get`, `sample`, `timestamp`, `version` and ``in``
        reads are recorded, of missing keys too; iterating keys is not.
        Concurrent tasks never record into each other's sets; a task created
        inside the block records into it until the block ends. Blocks nest:
        an outer block also records what an inner one reads.

        Examples:
            >>> store = StateStore({"bumper": False, "v": 0.0, "w": 0.0}, clock=lambda: 0.0)
            >>> with store.track_reads() as reads:
            ...     moving = store.v != 0 or store.get("w") != 0
            >>> sorted(reads)
            ['v', 'w']
        """
        return tracking(self)

    # -- writing --------------------------------------------------------------

    def set(self, key: str, value: Any) -> None:
        """Write ``value`` under ``key`` and notify its subscribers."""
        check_key(key)
        if self._loop is not None and not running_here(self._loop, self._ident):
            raise wrong_loop(f"write state key {key!r}", self._loop, self._thread)
        now = self._clock()
        self._values[key] = value
        self._ledger.write(key, now)
        self._subscribers.notify(key, value)

    def __setitem__(self, key: str, value: Any) -> None:
        self.set(key, value)

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _INTERNAL:
            object.__setattr__(self, name, value)
            return
        if name.startswith("_") or hasattr(type(self), name):
            why = "starts with '_'" if name.startswith("_") else "belongs to the store"
            raise AttributeError(
                f"cannot write state key {name!r} as an attribute: the name {why}; "
                f"write store[{name!r}] = value"
            )
        self.set(name, value)

    def __delitem__(self, key: str) -> None:
        raise TypeError(f"cannot delete state key {key!r}: keys are never deleted; write None")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"cannot delete {name!r}: state keys are never deleted; write None")

    def update(
        self,
        mapping: Mapping[str, Any] | Iterable[tuple[str, Any]] | None = None,
        /,
        **values: Any,
    ) -> None:
        """Write several keys as one batch: one timestamp, one notification.

        Each subscriber is called once, with the written keys it watches.
        Writing nothing does nothing.

        Examples:
            >>> store = StateStore(clock=lambda: 0.0)
            >>> store.update({"bumper_left": False}, bumper_right=True)
            >>> dict(store), store.version()
            ({'bumper_left': False, 'bumper_right': True}, 1)
        """
        changes: dict[str, Any] = {} if mapping is None else dict(mapping)
        if values:
            changes.update(values)
        self.write_owned(changes)

    def write_owned(self, changes: dict[str, Any]) -> None:
        """`update` with a dict the caller gives up: it is kept as it is, not copied.

        For backends writing a fresh dict of readings at every control tick;
        the caller must not change ``changes`` afterwards.

        Examples:
            >>> store = StateStore(clock=lambda: 0.0)
            >>> store.write_owned({"v": 0.25, "w": 0.0})
            >>> store.v, store.version()
            (0.25, 1)

        Raises:
            TypeError: ``changes`` is not a dict (use `update` for other mappings), or a
                key is not a string; nothing is written then.
        """
        if type(changes) is not dict:
            msg = (
                f"write_owned takes a dict of state keys to values, got {changes!r} "
                f"({type(changes).__name__}); use store.update(...) for other mappings"
            )
            raise TypeError(msg)
        if not changes:
            return
        if not changes.keys() <= self._values.keys():  # known keys are strings already
            for key in changes:
                check_key(key)
        loop = self._loop  # running_here(loop, ...), inlined: a backend writes at every tick
        if loop is not None and (get_ident() != self._ident or not loop.is_running()):
            raise wrong_loop(f"write state keys {sorted(changes)}", loop, self._thread)
        now = self._clock()
        keys = tuple(changes)
        self._values.update(changes)
        self._ledger.write_batch(keys, now, changes)  # O(1) for a sequence written before
        self._subscribers.notify_batch(changes, keys)

    def filtered(self, name: str, value: float, window: int = 10) -> float:
        """Add ``value`` to the moving window ``name`` and return the window's mean.

        pyRobots' ``robot.filtered``: the windows belong to this store (so to
        one robot) and are not state keys. Calling with another ``window``
        resizes that window, keeping its latest values.

        Raises:
            ValueError: ``window`` is not a positive integer.

        Examples:
            >>> store = StateStore()
            >>> [store.filtered("ir", v, window=2) for v in (1.0, 2.0, 4.0)]
            [1.0, 1.5, 3.0]
        """
        average = self._windows.get(name)
        if average is None:
            average = self._windows[name] = MovingAverage(window)
        elif average.window != window:
            average.resize(window)
        return average.add(value)

    def subscribe(
        self,
        callback: Callable[[Mapping[str, Any]], object],
        keys: str | Iterable[str] | None = None,
    ) -> Subscription:
        """Call ``callback(changes)`` synchronously after every write of the watched keys.

        ``changes`` is a read-only mapping of each written key (among those
        watched) to the value written. Callbacks run in subscription order,
        those watching every key first; one that raises is logged on
        ``pyrobots_aio.state`` and the others still run. (Un)subscribing during
        a notification takes effect at once: a new subscription is not called
        for the write being notified, a closed one is not called any more.

        Args:
            callback: Called with the changes.
            keys: A key, several keys, or None (every key). Keys need not exist yet.

        Returns:
            The `Subscription`; ``close()`` it to stop.

        Raises:
            ValueError: ``keys`` is empty.
            TypeError: A key is not a string.
        """
        return self._subscribers.add(callback, keys)

    # -- helpers ----------------------------------------------------------------

    def _unknown(self, key: object) -> UnknownStateKeyError:
        known = sorted(self._values)
        if not known:
            return UnknownStateKeyError(
                f"unknown state key {key!r}; the state is empty (nothing has written it yet)"
            )
        closest = difflib.get_close_matches(str(key), known, n=3)
        listed = f"{known[:_SHOWN_KEYS]}"
        if len(known) > _SHOWN_KEYS:
            listed += f" and {len(known) - _SHOWN_KEYS} more"
        return UnknownStateKeyError(
            f"unknown state key {key!r}; closest: {closest}; known keys: {listed}"
        )

    def __dir__(self) -> list[str]:
        keys = {k for k in self._values if k.isidentifier() and not k.startswith("_")}
        return sorted(set(super().__dir__()) | keys)

    def __repr__(self) -> str:
        return (
            f"<StateStore {len(self._values)} keys, version {self._ledger.writes}: "
            f"{_repr.repr(self._values)}>"
        )


_INTERNAL = frozenset(StateStore.__slots__)
