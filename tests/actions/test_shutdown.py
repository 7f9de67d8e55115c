"""Shutdown: no action starts at the root while the robot shuts down; options are checked."""

from __future__ import annotations

import asyncio
import types

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionDefinitionError,
    Outcome,
    Robot,
    RobotNotRunningError,
    action,
)

pytestmark = pytest.mark.virtual_time


@action
async def rest(robot: Robot) -> str:
    await robot.sleep(0.5)
    return "rested"


@action
async def walk(robot: Robot, log: list[str]) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        log.append(await rest(robot))  # a cleanup may start a child, even at shutdown
        raise


@action
async def chatter(robot: Robot) -> None:
    await robot.sleep(3600)


@pytest.mark.asyncio
async def test_no_root_action_starts_while_the_robot_shuts_down() -> None:
    log: list[str] = []
    refused: list[str] = []
    robot = Robot()

    async def app_task() -> None:  # another task of the application keeps starting actions
        for _ in range(100):
            await asyncio.sleep(0.1)
            try:
                chatter(robot)
            except RobotNotRunningError as error:
                refused.append(str(error))
                return

    async with robot:
        handle = walk(robot, log)
        app = asyncio.create_task(app_task())
        await robot.sleep(0.05)
        started_before = len(robot.handles())
    await app
    assert log == ["rested"]
    assert handle.outcome is Outcome.CANCELLED
    assert started_before == 1
    assert robot.handles() == []
    assert refused == [
        "cannot start action 'chatter': <Robot running> is shutting down; start it before "
        "leaving 'async with robot:', or from an action's cleanup"
    ]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"max_actions": 2.5}, "max_actions must be a positive integer or None, got 2.5"),
        ({"max_actions": True}, "max_actions must be a positive integer or None, got True"),
        ({"cancel_grace": None}, "cancel_grace must be a positive number of seconds, got None"),
        (
            {"cancel_grace": float("inf")},
            "cancel_grace must be a positive number of seconds, got inf",
        ),
    ],
)
def test_bad_options_are_refused(options: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message) as info:
        Robot(**options)  # type: ignore[arg-type]
    assert str(info.value) == message


def test_two_actions_of_one_name_cannot_both_be_attached() -> None:
    async def other_rest(robot: Robot) -> None:
        await robot.sleep(1)

    other_rest.__name__ = "rest"
    other_rest.__module__ = "other_behaviours"
    other = types.ModuleType("other_behaviours")
    other.rest = action(other_rest)  # type: ignore[attr-defined]
    Robot(actions=[rest, rest])  # the same action twice: attached once
    with pytest.raises(ActionDefinitionError) as info:
        Robot(actions=[rest, other])
    assert str(info.value) == (
        f"cannot attach action 'rest' from other_behaviours: an action of that name from "
        f"{__name__} is attached already; rename one of them"
    )
