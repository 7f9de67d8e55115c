"""The library's own random walk, explored: disturbances drawn, invariants checked, on FakeBase.

Each schedule below is one that exploring found breaking the walk, shrunk and
printed by `Scenario.explore`; kept as it was printed, it replays the bug, which
is fixed. The explorations are CI-sized (the derandomized ``ci`` profile, few
examples of short walks); ``PYROBOTS_AIO_EXPLORE=long`` searches longer.
"""

from __future__ import annotations

from typing import Literal

import pytest

from pyrobots_aio.sim.random_walk import WalkReport, random_walk
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    SAFETY,
    At,
    Bump,
    Hit,
    On,
    Scenario,
    completes,
    ends_docked,
)

MOTIONS = ("undock", "drive_distance", "rotate_angle", "navigate_to", "dock")


def walk(on_bump: Literal["cancel", "suspend"], moves: int = 3) -> Scenario[FakeBase]:
    async def behaviour(robot: FakeBase) -> WalkReport:
        return await random_walk(robot, moves=moves, seed=0, on_bump=on_bump)

    return Scenario(
        behaviour,
        base=FakeBase,
        disturbances=[Bump],
        boundaries=MOTIONS,
        invariants=[completes(), ends_docked(), *SAFETY],
        horizon=30.0,
        name="walk",
    )


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
