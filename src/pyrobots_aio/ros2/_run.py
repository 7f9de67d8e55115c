"""``run(main, *args, rate=R)``: a program's loop at the pace of a ``sim-node --rate R``."""

from __future__ import annotations

import asyncio
import math
from typing import TYPE_CHECKING, TypeVar, TypeVarTuple

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

T = TypeVar("T")
Ts = TypeVarTuple("Ts")


def scaled_loop(rate: float) -> asyncio.AbstractEventLoop:
    """A new event loop whose clock runs ``rate`` times faster than the wall clock, from 0.

    Its timers, sleeps and timeouts all follow it (``robot.sleep(1)`` lasts
    ``1 / rate`` wall-clock seconds); rate 1 is an ordinary loop.

    Raises:
        ValueError: ``rate`` is not a positive, finite number.
    """
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not 0 < rate < math.inf:
        msg = f"rate must be a positive number (simulated seconds per second), got {rate!r}"
        raise ValueError(msg)
    if rate == 1:
        return asyncio.new_event_loop()
    from ..cli._sim_node import ScaledTimeLoop

    return ScaledTimeLoop(float(rate))


def run(main: Callable[[*Ts], Coroutine[object, object, T]], *args: *Ts, rate: float = 1.0) -> T:
    """Run ``main(*args)`` on a loop `rate` times faster than real time; return its result.

    Beside ``pyrobots-aio sim-node --rate R`` (which simulates R seconds a
    second and publishes ``/clock``), ``run(main, rate=R)`` makes the
    program's seconds — ``robot.time()``, ``robot.sleep``, timeouts, a
    `Ros2Robot`'s ``odom_timeout`` — simulated seconds too.

    Example:
        >>> import asyncio
        >>> async def main() -> float:
        ...     loop = asyncio.get_running_loop()
        ...     start = loop.time()
        ...     await asyncio.sleep(2.0)  # 0.5 s of the wall clock
        ...     return round(loop.time() - start)
        >>> run(main, rate=4)
        2
    """
    loop = scaled_loop(rate)
    with asyncio.Runner(loop_factory=lambda: loop) as runner:
        return runner.run(main(*args))
