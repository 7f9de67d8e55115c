"""The firing rules of `Trigger`, driven step by step on a scripted clock."""

from __future__ import annotations

import heapq
import itertools
from typing import TYPE_CHECKING, Any, cast

from pyrobots_aio.events._trigger import Trigger

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable


class Timer:
    def __init__(self, callback: Callable[[], None]) -> None:
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class ScriptedLoop:
    """Just the clock and timers a trigger uses; time moves only through `advance`."""

    def __init__(self) -> None:
        self.now = 0.0
        self._timers: list[tuple[float, int, Timer]] = []
        self._order = itertools.count()

    def time(self) -> float:
        return self.now

    def call_at(self, when: float, callback: Callable[[], None], context: object = None) -> Timer:
        timer = Timer(callback)
        heapq.heappush(self._timers, (when, next(self._order), timer))
        return timer

    def call_later(
        self, delay: float, callback: Callable[[], None], context: object = None
    ) -> Timer:
        return self.call_at(self.now + delay, callback)

    def pending(self) -> list[float]:
        return sorted(when for when, _, timer in self._timers if not timer.cancelled)

    def advance(self, to: float) -> None:
        """Run the timers due up to ``to`` in time order, then stop the clock at ``to``."""
        while self._timers and self._timers[0][0] <= to:
            when, _, timer = heapq.heappop(self._timers)
            if not timer.cancelled:
                self.now = when
                timer.callback()
        self.now = to


def _trigger(**options: Any) -> tuple[ScriptedLoop, Trigger, list[tuple[float, object]]]:
    loop = ScriptedLoop()
    fired: list[tuple[float, object]] = []
    trigger = Trigger(
        cast("asyncio.AbstractEventLoop", loop),
        lambda value: fired.append((loop.now, value)),
        **options,
    )
    return loop, trigger, fired


def test_a_level_fires_on_the_rise_then_on_anchored_ticks_while_held() -> None:
    loop, trigger, fired = _trigger(edge=False, period=0.1)
    trigger.observe(True, "a")
    loop.advance(0.35)
    trigger.observe(True, "b")  # a new value while held: reported at the next tick
    loop.advance(0.45)
    trigger.observe(False, "c")
    loop.advance(10.0)
    assert fired == [(0.0, "a"), (0.1, "a"), (0.2, "a"), (0.30000000000000004, "a"), (0.4, "b")]
    assert loop.pending() == []


def test_a_tick_left_due_when_a_rise_fires_is_replaced_not_doubled() -> None:
    loop, trigger, fired = _trigger(edge=False, period=0.1)
    trigger.observe(True, 1)  # fires at 0.0, tick due at 0.1
    loop.now = 0.1  # the clock reaches the tick, but a write comes before it runs
    trigger.observe(False, 0)
    trigger.observe(True, 2)  # cool-down over: fires now, and the due tick is dropped
    loop.advance(0.15)
    assert fired == [(0.0, 1), (0.1, 2)]
    assert loop.pending() == [0.2]


def test_a_rise_in_the_cool_down_fires_at_its_end_with_the_value_that_rose() -> None:
    loop, trigger, fired = _trigger(edge=False, period=1.0)
    trigger.observe(True, 1)
    trigger.observe(False, 0)
    loop.advance(0.5)
    trigger.observe(True, 2)
    trigger.observe(False, 0)
    loop.advance(5.0)
    assert fired == [(0.0, 1), (1.0, 2)]


def test_an_edge_fires_once_per_rise_and_a_rearming_edge_fires_again_while_holding() -> None:
    _loop, edge, fired = _trigger(edge=True)
    for holds in (True, True, False, True):
        edge.observe(holds, holds)
    assert fired == [(0.0, True), (0.0, True)]
    _loop, rearming, again = _trigger(edge=True, rearm=True)
    for value in (1, 2, 3):
        rearming.observe(True, value)  # each observation that holds is a new edge
    assert again == [(0.0, 1), (0.0, 2), (0.0, 3)]


def test_a_primed_edge_needs_a_fall_first() -> None:
    _loop, trigger, fired = _trigger(edge=True)
    trigger.prime(True, "on")
    trigger.observe(True, "on")
    trigger.observe(False, "off")
    trigger.observe(True, "on")
    assert fired == [(0.0, "on")]


def test_held_for_starts_over_after_each_fall_and_stop_cancels_the_timers() -> None:
    loop, trigger, fired = _trigger(edge=False, period=0.5, held_for=1.0)
    trigger.observe(True, 1)
    loop.advance(0.9)
    trigger.observe(False, 0)
    trigger.observe(True, 2)
    loop.advance(2.4)
    assert fired == [(1.9, 2), (2.4, 2)]
    trigger.stop()
    assert loop.pending() == []
    trigger.observe(False, 0)
    trigger.observe(True, 3)
    loop.advance(10.0)
    assert fired == [(1.9, 2), (2.4, 2)]
    assert repr(trigger) == "<Trigger level period=0.5 held>"
