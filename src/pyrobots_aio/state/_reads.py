"""Read tracking: which keys of a store a block of code reads.

The event layer evaluates a predicate inside `StateStore.track_reads` and
re-evaluates it only when one of those keys changes. The log lives in a
context variable, so concurrent tasks never record into each other's sets.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterator
    from collections.abc import Set as AbstractSet


class ReadLog:
    """The keys read from one store inside one tracking block."""

    __slots__ = ("active", "keys", "outer", "store")

    def __init__(self, store: object, outer: ReadLog | None) -> None:
        self.store = store
        self.outer = outer
        self.keys: set[str] = set()
        self.active = True

    def record(self, store: object, key: str) -> None:
        """Record a read of ``key`` from ``store`` in every enclosing block on that store."""
        log: ReadLog | None = self
        while log is not None:  # an enclosing block depends on the key too
            if log.active and log.store is store:
                log.keys.add(key)
            log = log.outer


READS: ContextVar[ReadLog | None] = ContextVar("pyrobots_aio_state_reads", default=None)
"""The innermost tracking block of the current context; None when nothing tracks (the fast path)."""


@contextmanager
def tracking(store: object) -> Iterator[AbstractSet[str]]:
    """Track the reads of ``store`` until the block ends; yield the growing set of keys."""
    log = ReadLog(store, READS.get())
    token = READS.set(log)
    try:
        yield log.keys
    finally:
        log.active = False  # tasks started inside the block stop recording too
        READS.reset(token)
