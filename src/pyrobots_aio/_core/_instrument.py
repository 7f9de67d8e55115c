"""Instrumentation: every executive event, fanned out to registered instruments.

Recorders (JSON Lines, MCAP) and tests plug in here; the events are the
classes of `._events`. Emitting costs one truth test when no instrument is
registered, so the hot paths guard with ``if instruments:`` before building an
event.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ._events import EventKind, ExecEvent

if TYPE_CHECKING:
    from collections.abc import Iterator

# EventKind and ExecEvent too: modules import them from here, their home before `._events`.
__all__ = ["EventKind", "ExecEvent", "Instrument", "Instruments"]

_log = logging.getLogger("pyrobots_aio.instrument")


@runtime_checkable
class Instrument(Protocol):
    """Receives every executive event of the robot it is attached to.

    ``on_event`` runs synchronously inside the executive: keep it fast and never
    block (buffer and write in bulk, as the recorders do).
    """

    def on_event(self, event: ExecEvent) -> None:
        """Handle one event."""


class Instruments:
    """The instruments attached to one robot.

    Examples:
        >>> from pyrobots_aio import ActionStarted
        >>> hub = Instruments()
        >>> class Count:
        ...     n = 0
        ...     def on_event(self, event: ExecEvent) -> None:
        ...         self.n += 1
        >>> counter = Count()
        >>> hub.add(counter)
        >>> hub.emit(ActionStarted(0.0, 1, "walk"))
        >>> counter.n
        1
    """

    __slots__ = ("items",)

    def __init__(self) -> None:
        self.items: tuple[Instrument, ...] = ()
        """The instruments, in the order added (empty: hot paths skip building events)."""

    def add(self, instrument: Instrument) -> None:
        """Attach an instrument (an object with ``on_event(event)``)."""
        if not callable(getattr(instrument, "on_event", None)):
            msg = f"{instrument!r} is not an instrument: it needs an on_event(event) method"
            raise TypeError(msg)
        self.items = (*self.items, instrument)

    def remove(self, instrument: Instrument) -> None:
        """Detach an instrument; detaching one that is not attached does nothing."""
        self.items = tuple(i for i in self.items if i is not instrument)

    def __bool__(self) -> bool:
        return bool(self.items)

    def __iter__(self) -> Iterator[Instrument]:
        return iter(self.items)

    def emit(self, event: ExecEvent) -> None:
        """Send one event to every instrument; a failing instrument is logged, not fatal."""
        for instrument in self.items:
            try:
                instrument.on_event(event)
            except Exception:
                _log.exception("instrument %r failed on %s", instrument, event.kind)

    def __repr__(self) -> str:
        return f"<Instruments {list(self.items)!r}>"
