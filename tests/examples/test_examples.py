from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import pytest

from pyrobots_aio import Outcome

EXAMPLES = Path(__file__).parent.parent.parent / "examples"


def load_example(name: str) -> ModuleType:
    """Import ``examples/<name>.py`` as a module (without running its ``__main__`` part)."""
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_safe_walk() -> None:
    assert await load_example("safe_walk").main() is Outcome.CANCELLED


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_resources() -> None:
    outcomes = await load_example("resources").main()
    assert outcomes == {
        "lift_box": Outcome.SUCCEEDED,
        "wave_hand": Outcome.SUCCEEDED,
        "scratch_head": Outcome.SKIPPED,
        "long_lift_box": Outcome.CANCELLED,
        "catch_falling_cup": Outcome.SUCCEEDED,
    }


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_look_at() -> None:
    pan, tilt, x, y = await load_example("look_at").main()
    assert pan == pytest.approx(math.pi / 2)
    assert tilt == pytest.approx(math.pi / 4)
    assert (x, y) == (pytest.approx(0.0, abs=1e-12), pytest.approx(2.0))


@pytest.mark.asyncio
async def test_embedded() -> None:
    module: ModuleType = load_example("embedded")
    started, running, missing, after = await module.main()
    assert started == {"started": 1}
    assert running == [{"id": 1, "name": "patrol", "state": "running", "parent": None}]
    assert missing == {"error": "no route GET /nope"}
    assert after == []


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_master_controller() -> None:
    report = await load_example("master_controller").main()
    assert report == [
        "grasp_cup: cup grasped",
        "lift failed (arm controller timeout (attempt 1)); retrying in 0.1 s",
        "lift failed (arm controller timeout (attempt 2)); retrying in 0.2 s",
        "lift: cup lifted",
        "camera stream degraded: 6 Hz",
        "plan interrupted: emergency stop",
        "e-stop: everything cancelled, motors off",
        "safe pose",
        "pose safe, motors off",
    ]


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_random_walk_completes_with_every_bump_handled() -> None:
    report = await load_example("random_walk").main(seed=3)
    assert report.moves == 10
    assert report.bumps >= 1
    assert report.interrupted >= 1
    assert report.docked


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_kindergarten_session() -> None:
    session = await load_example("kindergarten").main(minutes=5, seed=1)
    assert session.minutes == 5
    assert 5 * 60 <= session.reactions["look"] <= 5 * 60 + 1  # one per second of the session
    assert session.reactions["blink"] > 5 * 60 / 6
    assert session.reactions["giggle"] > 0
    assert session.reactions["cry"] + session.reactions["thank"] > 0
    assert session.actions_per_minute > 60
    assert session.cap_hits == 0
