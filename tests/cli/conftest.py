"""A small recording for the replay command, made in virtual time (exact times)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import Resource, Robot, action, lock
from pyrobots_aio.recording import JsonlRecorder
from pyrobots_aio.sim import run

if TYPE_CHECKING:
    from pathlib import Path

ARM = Resource("arm")


@action
@lock(ARM)
async def wave(robot: Robot, seconds: float) -> None:
    await robot.sleep(seconds)


@action
async def greet(robot: Robot) -> None:
    await wave(robot, 1.0)
    await wave(robot, 2.0)


async def _main(path: Path) -> None:
    robot = Robot()
    with JsonlRecorder(path).attach(robot):
        async with robot:
            await greet(robot)
            last = wave(robot, 10.0)
            await robot.sleep(1.0)
            last.cancel("bored")
            await last.wait_done()


@pytest.fixture
def recording(tmp_path: Path) -> Path:
    """A recording of 4 actions over 4 s: greet#1 (wave#2, wave#3), then wave#4 cancelled."""
    path = tmp_path / "greet.jsonl"
    run(_main, path)
    return path
