"""The motion examples: the random walk on either base, kindergarten's wander and progress."""

from __future__ import annotations

import pytest
from test_examples import load_example

from pyrobots_aio import EventKind
from pyrobots_aio.testing import EventLog, inject_bump

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


async def test_a_bump_while_the_wander_undocks_does_not_end_the_wander() -> None:
    kindergarten = load_example("kindergarten")
    log = EventLog()
    async with kindergarten.Kid(seed=1, instruments=[log]) as robot:
        with inject_bump(robot, "undock") as bump:
            session = await kindergarten.session(robot, minutes=3, seed=1)
    assert bump.time is not None
    assert session.reactions["back_off"] >= 1  # the reflex ran ...
    assert log.outcomes("bumper_reflex")[0] == "succeeded"
    # ... and the wander went on moving until the session ended it
    assert log.outcomes("wander") == ["cancelled"]
    moves = [e.time for e in log.of_kind(EventKind.ACTION_STARTED, "move")]
    assert len([t for t in moves if t > bump.time]) >= 3


async def test_the_session_reports_its_progress_every_minute() -> None:
    shown: list[tuple[int, int, int]] = []

    def progress(minute: int, actions: int, events: int) -> None:
        shown.append((minute, actions, events))

    session = await load_example("kindergarten").main(minutes=3, seed=1, progress=progress)
    assert [minute for minute, _, _ in shown] == [1, 2, 3]
    assert sum(actions for _, actions, _ in shown) == session.actions_per_minute * 3
    assert max(actions for _, actions, _ in shown) == session.peak_actions_per_minute
    assert sum(events for _, _, events in shown) == session.events_per_minute * 3


@pytest.mark.parametrize("fake", [False, True])
async def test_the_random_walk_example_runs_on_the_simulator_and_in_memory(fake: bool) -> None:
    report = await load_example("random_walk").main(seed=2, fake=fake)
    assert (report.moves, report.docked) == (10, True)
    assert report.bumps >= 1
