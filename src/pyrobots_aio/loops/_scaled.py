"""Scaled time: a loop whose clock runs ``rate`` times faster than the wall clock.

``run_scaled(main, *args, rate=R)`` runs a program at the pace of a
``pyrobots-aio sim-node --rate R``.
"""

from __future__ import annotations

import asyncio
import math
import selectors
import time
from typing import TYPE_CHECKING, TypeVar, TypeVarTuple

from ._closing import SignalSafeLoop

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

T = TypeVar("T")
Ts = TypeVarTuple("Ts")

_SelectResult = list[tuple[selectors.SelectorKey, int]]


class _ScaledSelector(selectors.DefaultSelector):
    """The platform's selector, where a wait of ``t`` loop seconds lasts ``t / rate`` real ones."""

    def __init__(self, rate: float) -> None:
        super().__init__()
        self._rate = rate

    def select(self, timeout: float | None = None) -> _SelectResult:
        return super().select(None if timeout is None else timeout / self._rate)


class ScaledTimeLoop(SignalSafeLoop):
    """An event loop whose clock runs ``rate`` times faster than the wall clock, from 0.

    Timers, sleeps and timeouts all follow it, so a real-time `SimRobot` on
    this loop simulates ``rate`` seconds per second.
    """

    def __init__(self, rate: float) -> None:
        self._rate = rate
        self._origin = time.monotonic()
        super().__init__(_ScaledSelector(rate))

    def time(self) -> float:
        """Simulated seconds since the loop was made."""
        return (time.monotonic() - self._origin) * self._rate


def scaled_loop(rate: float) -> asyncio.AbstractEventLoop:
    """A new event loop whose clock runs ``rate`` times faster than the wall clock, from 0.

    Its timers, sleeps and timeouts all follow it (``robot.sleep(1)`` lasts
    ``1 / rate`` wall-clock seconds); rate 1 is an ordinary loop. Each lets go of
    the signal wake-up before it closes (`SignalSafeLoop`).

    Raises:
        ValueError: ``rate`` is not a positive, finite number.
    """
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not 0 < rate < math.inf:
        msg = f"rate must be a positive number (simulated seconds per second), got {rate!r}"
        raise ValueError(msg)
    if rate == 1:
        return SignalSafeLoop()
    return ScaledTimeLoop(float(rate))


def run_scaled(
    main: Callable[[*Ts], Coroutine[object, object, T]], *args: *Ts, rate: float = 1.0
) -> T:
    """Run ``main(*args)`` on a loop `rate` times faster than real time; return its result.

    Beside ``pyrobots-aio sim-node --rate R`` (which simulates R seconds a
    second and publishes ``/clock``), ``run_scaled(main, rate=R)`` makes the
    program's seconds — ``robot.time()``, ``robot.sleep``, timeouts, a
    `Ros2Robot`'s ``odom_timeout`` — simulated seconds too.

    Examples:
        >>> import asyncio
        >>> async def main() -> float:
        ...     loop = asyncio.get_running_loop()
        ...     start = loop.time()
        ...     await asyncio.sleep(2.0)  # 0.5 s of the wall clock
        ...     return round(loop.time() - start)
        >>> run_scaled(main, rate=4)
        2
    """
    loop = scaled_loop(rate)
    with asyncio.Runner(loop_factory=lambda: loop) as runner:
        return runner.run(main(*args))
