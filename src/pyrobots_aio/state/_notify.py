"""Change notification for the state store: subscriptions and their per-key index.

Writes cost O(subscribers of the written key): every-key subscribers sit in
one group, the others in a group per key. A group is an ordered set (O(1) to
join and leave, so closing a thousand monitors of one key is not quadratic)
with a tuple snapshot made when a write first needs it: a notification in
progress iterates its snapshot whatever (un)subscribes meanwhile.
A batch write finds its subscribers through a routing table cached per key
sequence, so the same couple of dozen keys written every control tick cost a
lookup, not a pass over every key.
"""

from __future__ import annotations

import itertools
import logging
from collections import deque
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping

    Subscriber = Callable[[Mapping[str, Any]], object]
    _Delivery = tuple[tuple["Subscription", ...], Mapping[str, Any]]
    _Routes = tuple[tuple["Subscription", tuple[str, ...]], ...]

_log = logging.getLogger("pyrobots_aio.state")
_ROUTES_KEPT = 64  # key sequences whose routing is cached (writers use a handful)


class Subscription:
    """A change callback registered with `StateStore.subscribe`; `close` it to stop.

    Also a context manager that closes it on exit.
    """

    __slots__ = ("_callback", "_closed", "_index", "_keys", "_order")

    def __init__(
        self,
        index: SubscriberIndex,
        callback: Subscriber,
        keys: frozenset[str] | None,
        order: int,
    ) -> None:
        self._index = index
        self._callback = callback
        self._keys = keys
        self._order = order
        self._closed = False

    @property
    def keys(self) -> frozenset[str] | None:
        """The keys watched, or None for every key."""
        return self._keys

    @property
    def closed(self) -> bool:
        """Whether `close` was called."""
        return self._closed

    def close(self) -> None:
        """Stop notifications at once, even for a write being notified right now."""
        if not self._closed:
            self._closed = True
            self._index.remove(self)

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __repr__(self) -> str:
        keys = "every key" if self._keys is None else f"keys={sorted(self._keys)}"
        state = " closed" if self._closed else ""
        name = getattr(self._callback, "__qualname__", type(self._callback).__qualname__)
        return f"<Subscription {name} {keys}{state}>"


class _Group:
    """The subscriptions of one key (or of every key), in subscription order."""

    __slots__ = ("_members", "_snapshot")

    def __init__(self) -> None:
        self._members: dict[Subscription, None] = {}
        self._snapshot: tuple[Subscription, ...] | None = ()

    def __bool__(self) -> bool:
        return bool(self._members)

    def add(self, sub: Subscription) -> None:
        self._members[sub] = None
        self._snapshot = None

    def discard(self, sub: Subscription) -> None:
        self._members.pop(sub, None)
        self._snapshot = None

    def snapshot(self) -> tuple[Subscription, ...]:
        """The members now, as a tuple kept until the next change."""
        snapshot = self._snapshot
        if snapshot is None:
            snapshot = self._snapshot = tuple(self._members)
        return snapshot


class SubscriberIndex:
    """The subscriptions of one store, indexed by key, and their in-order delivery."""

    __slots__ = ("_by_key", "_every", "_notifying", "_orders", "_pending", "_routes")

    def __init__(self) -> None:
        self._every = _Group()
        self._by_key: dict[str, _Group] = {}
        self._routes: dict[tuple[str, ...], _Routes] = {}
        self._orders = itertools.count()
        self._notifying = False
        self._pending: deque[_Delivery] = deque()

    def add(self, callback: Subscriber, keys: str | Iterable[str] | None) -> Subscription:
        """Register ``callback`` for ``keys`` (None: every key)."""
        watched = _watched(keys)
        sub = Subscription(self, callback, watched, next(self._orders))
        self._routes.clear()
        if watched is None:
            self._every.add(sub)
        else:
            for key in watched:
                group = self._by_key.get(key)
                if group is None:
                    group = self._by_key[key] = _Group()
                group.add(sub)
        return sub

    def remove(self, sub: Subscription) -> None:
        """Unregister ``sub`` (running notifications keep their snapshot)."""
        self._routes.clear()
        if sub.keys is None:
            self._every.discard(sub)
            return
        for key in sub.keys:
            group = self._by_key[key]
            group.discard(sub)
            if not group:
                del self._by_key[key]

    def notify(self, key: str, value: Any) -> None:
        """Tell the subscribers of ``key`` that ``value`` was written."""
        subs = self._every.snapshot()
        group = self._by_key.get(key)
        if group is not None:
            subs += group.snapshot()
        if subs:
            self._run([(subs, MappingProxyType({key: value}))])

    def notify_batch(self, changes: dict[str, Any], keys: tuple[str, ...]) -> None:
        """Tell each subscriber, once, the written keys it watches (``keys = tuple(changes)``)."""
        routes = self._routes.get(keys)
        if routes is None:
            routes = self._route(keys)
        deliveries: list[_Delivery] = []
        every = self._every.snapshot()
        if every:
            deliveries.append((every, MappingProxyType(changes)))
        for sub, watched in routes:
            if len(watched) == 1:  # (most watch one key: no comprehension's frame to make)
                key = watched[0]
                mine = {key: changes[key]}
            else:
                mine = {key: changes[key] for key in watched}
            deliveries.append(((sub,), MappingProxyType(mine)))
        if deliveries:
            self._run(deliveries)

    def _route(self, keys: tuple[str, ...]) -> _Routes:
        """Which subscribers watch which of ``keys`` (in write order), in subscription order.

        Cached per key sequence, since a backend writes the same keys every tick;
        (un)subscribing clears the cache.
        """
        per_sub: dict[Subscription, list[str]] = {}
        for key in keys:
            group = self._by_key.get(key)
            for sub in () if group is None else group.snapshot():
                per_sub.setdefault(sub, []).append(key)
        ordered = sorted(per_sub, key=lambda s: s._order)
        routes = tuple((sub, tuple(per_sub[sub])) for sub in ordered)
        if len(self._routes) >= _ROUTES_KEPT:
            self._routes.clear()
        self._routes[keys] = routes
        return routes

    def _run(self, deliveries: list[_Delivery]) -> None:
        if self._notifying:  # a subscriber wrote: deliver after the write being notified
            self._pending.extend(deliveries)
            return
        self._notifying = True
        pending = self._pending
        try:
            while True:
                for subs, changes in deliveries:
                    for sub in subs:
                        if sub._closed:
                            continue
                        try:
                            sub._callback(changes)
                        except Exception:
                            _log.exception(
                                "state subscriber %r failed on a write of %s", sub, sorted(changes)
                            )
                if not pending:
                    break
                deliveries = [pending.popleft()]  # what a subscriber wrote, in order
        finally:
            self._notifying = False
            if pending:
                pending.clear()


def check_key(key: object) -> None:
    """Raise TypeError unless ``key`` is a string."""
    if not isinstance(key, str):
        raise TypeError(f"state keys are strings, got {key!r} ({type(key).__name__})")


def _watched(keys: str | Iterable[str] | None) -> frozenset[str] | None:
    if keys is None:
        return None
    watched = frozenset((keys,)) if isinstance(keys, str) else frozenset(keys)
    if not watched:
        raise ValueError("keys is empty: pass None to watch every key")
    for key in watched:
        check_key(key)
    return watched
