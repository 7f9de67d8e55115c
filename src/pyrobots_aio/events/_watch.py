"""``robot.watch(key)``: every change of one state key, as an async iterator.

The store's subscriber puts each changed value into a bounded buffer (no user
code runs inside the write); the async generator hands them out in order. If
the consumer falls behind by more than ``buffer`` values, the oldest are
dropped (the freshest reading wins, as a robot wants) and counted, with one
warning. The iteration ends cleanly when the robot stops (or the monitors are
cancelled); breaking out of it unsubscribes once the iterator is closed or
dropped, also one that never gave a value.
"""

from __future__ import annotations

import asyncio
import math
import weakref
from collections import deque
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from .._core._logging import ScopedLogger
    from ..state import StateStore


def check_buffer(buffer: object) -> int:
    """Validate ``buffer`` (a positive int)."""
    if isinstance(buffer, bool) or not isinstance(buffer, int) or buffer < 1:
        msg = f"buffer must be a positive number of values, got {buffer!r}; e.g. buffer=64"
        raise ValueError(msg)
    return buffer


def same(a: object, b: object) -> bool:
    """Whether writing ``b`` after ``a`` is no change (NaN after NaN included; arrays: changed)."""
    if a is b:
        return True
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    try:
        return bool(a == b)
    except Exception:  # an array compares element-wise: call it a change
        return False


class Feed:
    """The buffer between one key's writes and one ``watch`` iteration."""

    __slots__ = (
        "_last",
        "_log",
        "_loop",
        "_subscription",
        "_waiter",
        "closed",
        "dropped",
        "key",
        "values",
    )

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        store: StateStore,
        key: str,
        buffer: int,
        log: ScopedLogger,
    ) -> None:
        self._loop = loop
        self._log = log
        self._last = store.get(key)
        self._waiter: asyncio.Future[None] | None = None
        self.key = key
        self.values: deque[Any] = deque(maxlen=buffer)
        self.closed = False
        self.dropped = 0
        self._subscription = store.subscribe(self.on_write, keys=key)

    def on_write(self, changes: Mapping[str, Any]) -> None:
        """The store's subscriber: keep the value if it changed."""
        value = changes[self.key]
        if same(self._last, value):
            return
        self._last = value
        values = self.values
        if len(values) == values.maxlen:
            if not self.dropped:
                self._log.warning(
                    "watch(%r) fell %d values behind; dropping the oldest (raise buffer= "
                    "or consume faster)",
                    self.key,
                    values.maxlen,
                )
            self.dropped += 1
        values.append(value)
        self._wake()

    def close(self) -> None:
        """Stop receiving; the iteration ends once the buffered values are taken."""
        self.closed = True
        self._subscription.close()
        self._wake()

    async def wait(self) -> None:
        """Wait until a value comes or the feed closes."""
        self._waiter = self._loop.create_future()
        try:
            await self._waiter
        finally:
            self._waiter = None

    def _wake(self) -> None:
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)


class Watch:
    """The async iterator ``robot.watch`` returns: the values of one `Feed`, in order.

    It unsubscribes when the feed closes, when `aclose` is called, or when it
    is dropped, whether or not it ever gave a value (an async generator's
    ``finally`` would never run for one that never started).
    """

    __slots__ = ("__weakref__", "_feed", "_release")

    def __init__(self, feed: Feed, forget: Callable[[Feed], None]) -> None:
        self._feed = feed
        self._release = weakref.finalize(self, _release, feed, forget)

    def __aiter__(self) -> Watch:
        return self

    async def __anext__(self) -> Any:
        feed = self._feed
        while not feed.values:
            if feed.closed:
                self._release()
                raise StopAsyncIteration
            await feed.wait()
        return feed.values.popleft()

    async def aclose(self) -> None:
        """Stop watching now (what ``break`` then collection would do, at once)."""
        self._release()

    def __repr__(self) -> str:
        feed = self._feed
        state = "closed" if feed.closed else f"{len(feed.values)} buffered"
        return f"<watch {feed.key!r} {state}>"


def _release(feed: Feed, forget: Callable[[Feed], None]) -> None:
    feed.close()
    forget(feed)
