"""The waiting line of one plain resource: requests in service order.

Service order is rank first (higher first: the priority, or with aging the
priority raised by the time waited, see `ResourceManager.aging`), then first
come first served;
a preempting request gets no place ahead of earlier requests of its priority
(DESIGN §4: nobody overtakes an earlier request of equal or higher priority).
Requests of one priority band sit in a deque in arrival order; a request that
stops waiting (granted or withdrawn) is dropped lazily when it reaches the
front, and a band is compacted when dead entries outnumber live ones, so every
operation is O(1) amortized apart from creating a new band (O(bands)).
"""

from __future__ import annotations

import bisect
from collections import deque
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

if TYPE_CHECKING:
    from collections.abc import Iterator


class Queued(Protocol):
    """What the queue needs of a request."""

    @property
    def key(self) -> tuple[float, int]:
        """Sort key: ``(-rank, arrival number)``; the rank is the priority, aged or not."""

    @property
    def waiting(self) -> bool:
        """Whether the request still waits (False once granted or withdrawn)."""


Q = TypeVar("Q", bound=Queued)


class _Band(Generic[Q]):
    __slots__ = ("items", "live")

    def __init__(self) -> None:
        self.items: deque[Q] = deque()
        self.live = 0


class WaitQueue(Generic[Q]):
    """Waiting requests of one resource, iterated in service order."""

    __slots__ = ("_bands", "_order")

    def __init__(self) -> None:
        self._bands: dict[float, _Band[Q]] = {}
        self._order: list[float] = []

    def add(self, request: Q) -> None:
        """Queue ``request`` (it must be waiting) behind the others of its band."""
        band_key = request.key[0]
        band = self._bands.get(band_key)
        if band is None:
            band = _Band()
            self._bands[band_key] = band
            bisect.insort(self._order, band_key)
        band.items.append(request)
        band.live += 1

    def discard(self, request: Q) -> None:
        """Forget ``request``, which has just stopped waiting."""
        band_key = request.key[0]
        band = self._bands[band_key]
        band.live -= 1
        if band.live == 0:
            del self._bands[band_key]
            self._order.remove(band_key)
        elif len(band.items) > 2 * band.live + 8:
            band.items = deque(r for r in band.items if r.waiting)

    def first(self) -> Q | None:
        """The request served next, or None if nobody waits."""
        if not self._order:
            return None
        items = self._bands[self._order[0]].items
        while not items[0].waiting:
            items.popleft()
        return items[0]

    def __iter__(self) -> Iterator[Q]:
        """Waiting requests in service order (do not change the queue meanwhile)."""
        for band_key in self._order:
            for request in self._bands[band_key].items:
                if request.waiting:
                    yield request

    def __bool__(self) -> bool:
        return bool(self._order)

    def __len__(self) -> int:
        return sum(band.live for band in self._bands.values())
