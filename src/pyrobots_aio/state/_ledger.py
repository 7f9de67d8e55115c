"""When each state key was last written, and how many times: the store's timestamps and versions.

A backend writes the same couple of dozen keys every control tick, and the
timestamps and versions of a key are read far less often than they are
written. So a batch write does not stamp and count each key: it stamps and
counts its key sequence once (a `_Batch`), and a read of one key combines the
batches holding it with what single writes recorded. A key's version is the
number of writes of it, whichever way; its timestamp is that of its latest
write, found by write order. Past `_BATCHES_KEPT` distinct key sequences, the
batches are folded into the per-key tables. The keys of the latest write are
answered first, without a look-up: a recorder sampling the keys being written
asks right away.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Container

__all__ = ["WriteLedger"]

_BATCHES_KEPT = 64  # key sequences counted as a whole (writers use a handful)


class _Batch:
    """The writes of one key sequence: how many, and the latest one's time and order."""

    __slots__ = ("count", "keys", "order", "stamp")

    def __init__(self, keys: tuple[str, ...]) -> None:
        self.keys = keys
        self.count = 0
        self.stamp = 0.0
        self.order = 0


class WriteLedger:
    """Per-key timestamps and versions of a store's writes.

    Examples:
        >>> ledger = WriteLedger()
        >>> ledger.write("v", 1.0)
        >>> ledger.write_batch(("v", "w"), 2.0, {"v", "w"})
        >>> ledger.stamp("v"), ledger.version("v"), ledger.version("w")
        (2.0, 2, 1)
    """

    __slots__ = (
        "_batches",
        "_by_key",
        "_latest_keys",
        "_latest_stamp",
        "_orders",
        "_stamps",
        "_versions",
        "_writes",
    )

    def __init__(self) -> None:
        self._writes = 0  # write operations so far: orders the writes
        self._stamps: dict[str, float] = {}  # of single writes and folded batches
        self._orders: dict[str, int] = {}
        self._versions: dict[str, int] = {}
        self._batches: dict[tuple[str, ...], _Batch] = {}
        self._by_key: dict[str, tuple[_Batch, ...]] = {}
        self._latest_keys: Container[str] = ()  # those of the latest write, and its stamp
        self._latest_stamp = 0.0

    @property
    def writes(self) -> int:
        """How many write operations were recorded (a batch is one)."""
        return self._writes

    def write(self, key: str, now: float) -> None:
        """Record a write of ``key`` at ``now``."""
        self._latest_keys, self._latest_stamp = (key,), now
        self._writes += 1
        self._stamps[key] = now
        self._orders[key] = self._writes
        self._versions[key] = self._versions.get(key, 0) + 1

    def write_batch(self, keys: tuple[str, ...], now: float, written: Container[str]) -> None:
        """Record one write of every key of ``keys`` (no key twice) at ``now``.

        ``written`` holds the same keys, for a fast ``in`` (the dict written).
        """
        self._latest_keys, self._latest_stamp = written, now
        batch = self._batches.get(keys)
        if batch is None:
            batch = self._add(keys)
        self._writes += 1
        batch.count += 1
        batch.stamp = now
        batch.order = self._writes

    def stamp(self, key: str) -> float:
        """Return when ``key`` was last written; KeyError if never."""
        if key in self._latest_keys:
            return self._latest_stamp
        stamp = self._stamps.get(key)
        order = self._orders.get(key, 0)
        for batch in self._by_key.get(key, ()):
            if batch.order > order:
                stamp, order = batch.stamp, batch.order
        if stamp is None:
            raise KeyError(key)
        return stamp

    def version(self, key: str) -> int:
        """Return how many times ``key`` was written; KeyError if never."""
        version = self._versions.get(key, 0)
        for batch in self._by_key.get(key, ()):
            version += batch.count
        if not version:
            raise KeyError(key)
        return version

    def _add(self, keys: tuple[str, ...]) -> _Batch:
        if len(self._batches) >= _BATCHES_KEPT:
            self._fold()
        batch = self._batches[keys] = _Batch(keys)
        for key in keys:
            self._by_key[key] = (*self._by_key.get(key, ()), batch)
        return batch

    def _fold(self) -> None:
        """Move the batches' counts and latest stamps into the per-key tables."""
        for batch in self._batches.values():
            for key in batch.keys:
                self._versions[key] = self._versions.get(key, 0) + batch.count
                if batch.order > self._orders.get(key, 0):
                    self._stamps[key] = batch.stamp
                    self._orders[key] = batch.order
        self._batches.clear()
        self._by_key.clear()
