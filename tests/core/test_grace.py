"""The grace ladder: escalate one grace after a cancellation, abandon one grace later."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio._core._grace import Ladder, Stage

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]


async def test_each_item_escalates_then_is_abandoned_a_grace_apart() -> None:
    loop = asyncio.get_running_loop()
    seen: list[tuple[str, Stage, float]] = []

    def step(item: str, stage: Stage) -> bool:
        seen.append((item, stage, loop.time()))
        return True

    ladder = Ladder(loop, 2.0, step)
    ladder.watch("a")
    await asyncio.sleep(1)
    ladder.watch("b")
    await asyncio.sleep(10)
    assert seen == [
        ("a", Stage.ESCALATE, 2.0),
        ("b", Stage.ESCALATE, 3.0),
        ("a", Stage.ABANDON, 4.0),
        ("b", Stage.ABANDON, 5.0),
    ]


async def test_an_escalation_that_returns_false_ends_the_ladder() -> None:
    loop = asyncio.get_running_loop()
    seen: list[Stage] = []

    def step(item: str, stage: Stage) -> bool:
        seen.append(stage)
        return False  # done meanwhile, or left to others

    ladder = Ladder(loop, 1.0, step)
    ladder.watch("x")
    await asyncio.sleep(5)
    assert seen == [Stage.ESCALATE]


async def test_a_step_may_watch_more_and_close_stops_everything() -> None:
    loop = asyncio.get_running_loop()
    seen: list[tuple[str, Stage, float]] = []

    def step(item: str, stage: Stage) -> bool:
        seen.append((item, stage, loop.time()))
        if item == "parent" and stage is Stage.ESCALATE:
            ladder.watch("cleanup")  # a cleanup cut short is watched in turn
        return True

    ladder = Ladder(loop, 1.0, step)
    ladder.watch("parent")
    await asyncio.sleep(2.5)
    ladder.close()
    await asyncio.sleep(10)
    assert seen == [
        ("parent", Stage.ESCALATE, 1.0),
        ("cleanup", Stage.ESCALATE, 2.0),  # watched before the parent's next stage
        ("parent", Stage.ABANDON, 2.0),
    ]
