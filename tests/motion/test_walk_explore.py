"""The library's own random walk, explored: disturbances drawn, invariants checked, on FakeBase.

Each schedule below is one that exploring found breaking the walk, shrunk and
printed by `Scenario.explore`; kept as it was printed, it replays the bug, which
is fixed. The explorations are CI-sized (the derandomized ``ci`` profile, few
examples of short walks); ``PYROBOTS_AIO_EXPLORE=long`` searches longer.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import pytest

from pyrobots_aio.sim.random_walk import WalkReport, random_walk
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    SAFETY,
    At,
    Bump,
    Cancel,
    Cliff,
    EmergencyStop,
    Hit,
    On,
    Pause,
    Preempt,
    Reading,
    Scenario,
    completes,
    ends_docked,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from pyrobots_aio.testing.explore import Disturbance, Invariant

MOTIONS = ("undock", "drive_distance", "rotate_angle", "navigate_to", "dock")


HANDLED: list[type[Disturbance]] = [Bump, Cliff, Reading, Pause, Preempt]
"""What the walk must get through and still dock."""
STOPPING: list[type[Disturbance]] = [Bump, Cancel, EmergencyStop, Preempt, Pause]
"""What may end the walk early; it must stay safe."""


def walk(
    on_bump: Literal["cancel", "suspend"],
    disturbances: Sequence[type[Disturbance]] = (Bump,),
    invariants: Sequence[Invariant] = (completes(), ends_docked(), *SAFETY),
) -> Scenario[FakeBase]:
    async def behaviour(robot: FakeBase) -> WalkReport:
        return await random_walk(robot, moves=3, seed=0, on_bump=on_bump)

    return Scenario(
        behaviour,
        base=FakeBase,
        disturbances=disturbances,
        boundaries=MOTIONS,
        invariants=invariants,
        horizon=30.0,
        name="walk",
    )


@pytest.mark.explore(examples=8)
@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
def test_the_walk_gets_through_what_it_handles_and_docks(
    explore: Callable[[Scenario[FakeBase]], None], on_bump: Literal["cancel", "suspend"]
) -> None:
    explore(walk(on_bump, HANDLED))


@pytest.mark.explore(examples=8)
@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
def test_the_walk_stays_safe_when_stopped_cancelled_or_preempted(
    explore: Callable[[Scenario[FakeBase]], None], on_bump: Literal["cancel", "suspend"]
) -> None:
    explore(walk(on_bump, STOPPING, SAFETY))


@pytest.mark.parametrize("on_bump", ["cancel", "suspend"])
def test_a_bump_while_the_reflex_turns_is_not_driven_into(
    on_bump: Literal["cancel", "suspend"],
) -> None:
    # found by exploring: a bump as the walk left the dock made the reflex back off (it stalled
    # on the dock) and turn; turning, it touched the dock again; that press came while the
    # reflex ran, so no second reflex started, and the walk drove forward into the dock
    walk(on_bump).replay([
        Hit(Bump(), On('undock', at='end')),
        Hit(Bump(), At(0.06)),
    ])  # fmt: skip
