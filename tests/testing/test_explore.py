"""Explore: a planted bug is found, shrunk to one hit, printed as code that replays it.

The planted bug is the Create 3 script's: a walk whose bump reflex is not
armed while it undocks. A held bump then meets no reflex, and the undock
drives on into it. Exploring must find that within a CI-sized budget, shrink
it to that one bump, and print code that, run, fails the same way.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import ActionInterrupted, InvariantViolation
from pyrobots_aio.recording import load
from pyrobots_aio.sim.random_walk import bumper_reflex
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    Hit,
    Scenario,
    completes,
    no_forward_into_bumper,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    Walk = Callable[[FakeBase], Awaitable[None]]

pytest_plugins = ["pytester"]


async def careless_walk(robot: FakeBase) -> None:
    """Undock, then arm the reflex (too late), and drive out."""
    await robot.undock()
    await _drive_out(robot)


async def armed_walk(robot: FakeBase) -> None:
    """The fix: the reflex is armed before the undock."""
    await _drive_out(robot, robot.undock)


async def _drive_out(robot: FakeBase, first: Callable[[], Awaitable[None]] | None = None) -> None:
    reflex = robot.whenever("bumper", becomes=True).do(bumper_reflex)
    try:
        with contextlib.suppress(ActionInterrupted):  # the reflex took over
            if first is not None:
                await first()
            await robot.drive_distance(0.3)
    finally:
        await reflex.close()


def careless(
    behaviour: Callable[[FakeBase], Awaitable[None]] = careless_walk,
) -> Scenario[FakeBase]:
    return Scenario(
        behaviour,
        base=FakeBase,
        disturbances=[Bump],
        boundaries=["undock", "drive_distance"],
        invariants=[completes(), no_forward_into_bumper()],
        horizon=5.0,
        name="walk",
    )


FOUND = """\
walk broke its invariants under 1 hit(s):
  - at t=0.220 the base drove forward (v=0.200 m/s) with the front bumper pressed since t=0.000 \
(more than 0.2 s)
replay it in a test:

from pyrobots_aio.testing.explore import At, Bump, Hit
walk.replay([
    Hit(Bump(hold=0.5), At(0.0)),
])
"""


def test_the_unarmed_undock_is_found_and_shrunk_to_one_bump(tmp_path: Path) -> None:
    with pytest.raises(InvariantViolation) as found:
        careless().explore(examples=100, record_dir=tmp_path)
    message = str(found.value)
    assert message.startswith(FOUND)
    assert found.value.schedule == (Hit(Bump(hold=0.5), At(0.0)),)  # as it leaves the dock
    recording, page = tmp_path / "walk.jsonl", tmp_path / "walk.html"
    assert message.endswith(f"\nrecording: {recording}\nreplay page: {page}")
    assert "disturbance" in load(recording).samples  # the page marks the hit where it came
    assert page.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")


def test_the_printed_code_replays_the_failure() -> None:
    with pytest.raises(InvariantViolation) as found:
        careless().explore(examples=100)
    code = str(found.value).split("replay it in a test:\n\n")[1].split("\nrecording:")[0]
    with pytest.raises(InvariantViolation) as replayed:
        exec(code, {"walk": careless()})
    assert replayed.value.violations == found.value.violations


def test_the_fixed_walk_replays_clean() -> None:
    run = careless(armed_walk).replay([Hit(Bump(hold=0.5), At(0.0))])
    assert (run.violations, run.error, [hit for _, hit in run.hits]) == (
        [],
        None,
        [Hit(Bump(hold=0.5), At(0.0))],
    )
