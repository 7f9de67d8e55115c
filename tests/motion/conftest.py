"""The bases every motion test runs on: one fixture parameter per `DriveBase`.

A base joins the suite with one entry in `BASES`: how to make it (a robot
not yet started) and how to read its true pose in ``map`` (the simulator's
physics, the fake's world; a real robot's own localisation).

The suite's modules run on the virtual-time loop (``virtual_time``):
pytest-asyncio picks a test function's loop once for all its parameters
(at collection, from the function's marks), so a base that must follow the
wall clock (a ROS 2 robot driving another process) runs the same test
functions from a module of its own: ``from test_motion import *`` with no
``virtual_time`` mark and its own ``base`` fixture returning a `Base`
(``truth`` can be ``lambda robot: robot.map_pose()`` there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio.sim import SimRobot
from pyrobots_aio.testing import FakeBase

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio import DriveBase
    from pyrobots_aio.motion import Pose2D


@dataclass(frozen=True)
class Base:
    """How to make one kind of base, and read where it really is."""

    make: Callable[..., DriveBase]
    truth: Callable[[Any], Pose2D]


BASES = {
    "fake": Base(make=FakeBase, truth=lambda robot: robot.world.base_pose()),
    "sim": Base(make=SimRobot, truth=lambda robot: robot.world.base_pose()),
}


@pytest.fixture(params=sorted(BASES))
def base(request: pytest.FixtureRequest) -> Base:
    """Each kind of base in turn (the test makes and runs its robot with ``base.make()``)."""
    kind: Base = BASES[request.param]
    return kind
