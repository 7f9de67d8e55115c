"""When a condition fires: edges, levels with a rate limit, and ``held_for``.

A `Trigger` is fed observations ``(holds, value)`` — one per write of the key,
or per evaluation of the predicate — and calls ``fire(value)`` synchronously:

- **held**: the condition holds and has held for ``held_for`` seconds (a timer
  started when it began to hold; cancelled if it stops holding first).
- **edge**: fires once each time it becomes held.
- **level**: fires when it becomes held, then again every ``period`` seconds
  while it stays held (a ``call_at`` timer: no work while nothing holds). A
  level that becomes held again during the cool-down after a firing is
  remembered and fires when the cool-down ends, even if it no longer holds
  then, so no pulse is lost and there are at most ``1 / period`` firings a
  second. With ``period == 0`` (unlimited) every observation that finds it
  held fires, and nothing fires without an observation.

Re-firings land on ``anchor + n * period``, so they never drift.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable
    from contextvars import Context


class Trigger:
    """Decides, from successive observations of a condition, when it fires."""

    __slots__ = (
        "_anchor",
        "_context",
        "_count",
        "_edge",
        "_fire",
        "_held",
        "_hold",
        "_hold_timer",
        "_holds",
        "_loop",
        "_next_at",
        "_pending",
        "_pending_value",
        "_period",
        "_rearm",
        "_stopped",
        "_timer",
        "_value",
    )

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        fire: Callable[[Any], None],
        *,
        edge: bool,
        rearm: bool = False,
        held_for: float = 0.0,
        period: float = 0.0,
        context: Context | None = None,
    ) -> None:
        self._loop = loop
        self._fire = fire
        self._edge = edge
        self._rearm = rearm  # after an edge fires, holding again is a new edge (increase=)
        self._hold = held_for
        self._period = period
        self._context = context
        self._holds = False
        self._held = False
        self._value: Any = None
        self._hold_timer: asyncio.TimerHandle | None = None
        self._timer: asyncio.TimerHandle | None = None
        self._next_at = -float("inf")
        self._anchor = 0.0
        self._count = 0
        self._pending = False
        self._pending_value: Any = None
        self._stopped = False

    def prime(self, holds: bool, value: Any) -> None:
        """Set the initial state without firing (an edge only fires on a later change)."""
        self._holds = self._held = holds
        self._value = value

    def observe(self, holds: bool, value: Any) -> None:
        """Take one observation: does the condition hold, and on which value."""
        if self._stopped:
            return
        self._value = value
        was = self._holds
        self._holds = holds
        if not holds:
            if was:
                self._fall()
        elif not was:
            self._rise()
        elif self._held and not self._edge and self._period == 0:
            self._fire(value)

    def stop(self) -> None:
        """Fire no more; cancel the timers."""
        self._stopped = True
        for timer in (self._hold_timer, self._timer):
            if timer is not None:
                timer.cancel()
        self._hold_timer = self._timer = None

    # -- holding --------------------------------------------------------------

    def _rise(self) -> None:
        if self._hold > 0:
            self._hold_timer = self._loop.call_later(
                self._hold, self._hold_done, context=self._context
            )
        else:
            self._become_held()

    def _fall(self) -> None:
        self._held = False
        if self._hold_timer is not None:
            self._hold_timer.cancel()
            self._hold_timer = None

    def _hold_done(self) -> None:
        self._hold_timer = None
        self._become_held()

    def _become_held(self) -> None:
        self._held = True
        if self._edge:
            if self._rearm:
                self._holds = self._held = False
            self._fire(self._value)
        elif self._period == 0:
            self._fire(self._value)
        elif self._loop.time() >= self._next_at:
            self._fire_level(self._loop.time(), fresh=True)
        else:  # cool-down: fire when it ends, whatever happens meanwhile
            self._pending = True
            self._pending_value = self._value
            self._arm()

    # -- level re-firing ----------------------------------------------------------

    def _fire_level(self, at: float, *, fresh: bool) -> None:
        if fresh:
            self._anchor, self._count = at, 0
        else:
            self._count += 1
        self._next_at = self._anchor + (self._count + 1) * self._period
        if self._timer is not None:  # a tick due now, not yet run: the new one replaces it
            self._timer.cancel()
            self._timer = None
        value = self._value if self._held else self._pending_value
        self._pending = False
        self._fire(value)
        if self._held:
            self._arm()

    def _arm(self) -> None:
        if self._timer is None and not self._stopped:
            self._timer = self._loop.call_at(self._next_at, self._tick, context=self._context)

    def _tick(self) -> None:
        self._timer = None
        if self._pending or self._held:
            self._fire_level(self._next_at, fresh=False)

    def __repr__(self) -> str:
        kind = "edge" if self._edge else f"level period={self._period}"
        state = "held" if self._held else ("holding" if self._holds else "idle")
        return f"<Trigger {kind} {state}>"
