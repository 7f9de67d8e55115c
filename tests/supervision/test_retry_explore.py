"""retry under the emergency stop, explored: once the stop has latched, no attempt starts again.

DESIGN §13: while the stop is latched no supervised plan carries on, and
`retry` never retries `EmergencyStopError` (nor cancellation). Exploring
drops stops (cleared after a while, or not), pauses and preempting reflexes
anywhere in a plan whose attempts drive and then fail.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import ActionStarted, ExecEvent, action, exponential, retry
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    SAFETY,
    EmergencyStop,
    Invariant,
    Pause,
    Preempt,
    Scenario,
)

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio import Robot


@retry(4, backoff=exponential(0.5, factor=2))
@action
async def attempt(robot: FakeBase) -> None:
    await robot.drive_distance(0.2)
    await robot.drive_distance(-0.2)
    raise RuntimeError("slipped")


class no_attempt_after_a_stop(Invariant):
    """No attempt starts once the emergency stop has latched (cleared or not)."""

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        stopped: list[float] = []

        def on_stop(_: str) -> list[Any]:
            stopped.append(robot.time())
            return []

        class Attempts:
            def on_event(self, event: ExecEvent) -> None:
                if isinstance(event, ActionStarted) and event.name == "attempt" and stopped:
                    fail(f"at t={event.time:.3f} an attempt started after the stop at {stopped}")

        robot.add_emergency_stop_callback(on_stop)
        robot.instruments.add(Attempts())


async def plan(robot: FakeBase) -> None:
    await robot.undock()
    await attempt(robot)


@pytest.mark.explore(examples=10)
def test_retry_never_attempts_again_once_stopped(
    explore: Callable[[Scenario[FakeBase]], None],
) -> None:
    explore(
        Scenario(
            plan,
            base=FakeBase,
            disturbances=[EmergencyStop, EmergencyStop(None), Pause, Preempt],
            boundaries=("attempt", "drive_distance"),
            invariants=[no_attempt_after_a_stop(), *SAFETY],
            horizon=8.0,
            name="plan",
        )
    )
