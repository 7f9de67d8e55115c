"""A second cancel never kills cleanup (DESIGN §11): double clicks, ancestors, reaping, shutdown."""

from __future__ import annotations

import asyncio
import logging

import pytest

from log_support import logged
from pyrobots_aio import ActionCancelled, ActionHandle, Outcome, Robot, action
from pyrobots_aio.actions import current_action

pytestmark = pytest.mark.virtual_time

GRACE = 2.0


@action
async def rest(robot: Robot, log: list[str], seconds: float = 0.5) -> str:
    await robot.sleep(seconds)
    log.append("rested")
    return "at rest"


@action
async def walk(robot: Robot, log: list[str], rest_for: float = 0.5) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        log.append(await rest(robot, log, rest_for))  # the cleanup starts an action
        raise


@action
async def parent(robot: Robot, log: list[str], children: list[ActionHandle[None]]) -> None:
    children.append(walk(robot, log))
    await robot.sleep(3600)


def _cleanup_of(robot: Robot, handle: ActionHandle[None]) -> ActionHandle[str]:
    (child,) = handle.children
    assert child.name == "rest"
    return child  # type: ignore[return-value]


def _warnings(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in logged(caplog, logging.WARNING)]


@pytest.mark.asyncio
async def test_a_double_clicked_stop_lets_the_cleanup_finish(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = walk(robot, log)
        await robot.sleep(0.1)
        handle.cancel("stop")
        await robot.sleep(0.1)
        cleanup = _cleanup_of(robot, handle)
        assert handle.cancel("stop again") is True  # not done yet: still True
        assert await handle.wait_done() is Outcome.CANCELLED
    assert log == ["rested", "at rest"]
    assert cleanup.outcome is Outcome.SUCCEEDED
    assert handle.cancel_reason == "stop"
    assert _warnings(caplog) == []


@pytest.mark.asyncio
async def test_cancelling_the_parent_of_a_cancelled_child_spares_its_cleanup(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    children: list[ActionHandle[None]] = []
    async with Robot(cancel_grace=GRACE) as robot:
        top = parent(robot, log, children)
        await robot.sleep(0.1)
        (child,) = children
        child.cancel("child first")
        await robot.sleep(0.1)
        cleanup = _cleanup_of(robot, child)
        top.cancel("then the parent")
        assert await top.wait_done() is Outcome.CANCELLED
    assert cleanup.outcome is Outcome.SUCCEEDED
    assert child.cancel_reason == "child first"
    assert log == ["rested", "at rest"]
    assert _warnings(caplog) == []


@action
async def short_parent(robot: Robot, log: list[str], children: list[ActionHandle[None]]) -> None:
    children.append(walk(robot, log))
    await robot.sleep(0.2)  # the body ends while the child's cleanup runs


@pytest.mark.asyncio
async def test_a_parent_reaping_its_children_spares_their_cleanup(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    children: list[ActionHandle[None]] = []
    async with Robot(cancel_grace=GRACE) as robot:
        top = short_parent(robot, log, children)
        await robot.sleep(0.1)
        (child,) = children
        child.cancel("child first")
        await robot.sleep(0.05)
        cleanup = _cleanup_of(robot, child)
        assert await top.wait_done() is Outcome.SUCCEEDED
    assert cleanup.outcome is Outcome.SUCCEEDED
    assert child.cancel_reason == "child first"
    assert _warnings(caplog) == []


@pytest.mark.asyncio
async def test_robot_shutdown_spares_cleanup_started_before_it(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = walk(robot, log)
        await robot.sleep(0.1)
        handle.cancel("stop")
        await robot.sleep(0.1)
        cleanup = _cleanup_of(robot, handle)
    assert cleanup.outcome is Outcome.SUCCEEDED
    assert log == ["rested", "at rest"]
    assert _warnings(caplog) == []


@pytest.mark.asyncio
async def test_cleanup_is_bounded_by_the_grace_counted_from_the_first_cancel(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = walk(robot, log, 3600)  # a cleanup that would never end
        await robot.sleep(0.1)
        first = robot.time()
        handle.cancel("stop")
        await robot.sleep(1.5)
        cleanup = _cleanup_of(robot, handle)
        handle.cancel("stop again")  # does not restart the grace, nor cut the cleanup now
        assert not cleanup.cancel_requested
        assert await cleanup.wait_done() is Outcome.CANCELLED
        assert robot.time() == pytest.approx(first + GRACE)
        assert await handle.wait_done() is Outcome.CANCELLED
    assert log == []
    warnings = _warnings(caplog)
    assert warnings[0].startswith(
        f"action walk#1 still running {GRACE:g} s after cancellation, at "
    )


@action
async def fire_and_forget_cleanup(robot: Robot, log: list[str], spawned: list[object]) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        spawned.append(rest(robot, log, 3600))  # started, not awaited: the body ends
        raise


@pytest.mark.asyncio
async def test_an_unawaited_cleanup_action_is_cut_at_the_grace(
    caplog: pytest.LogCaptureFixture,
) -> None:
    log: list[str] = []
    spawned: list[object] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = fire_and_forget_cleanup(robot, log, spawned)
        await robot.sleep(0.1)
        first = robot.time()
        handle.cancel("stop")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert robot.time() == pytest.approx(first + GRACE)
    (cleanup,) = spawned
    assert isinstance(cleanup, ActionHandle)
    assert cleanup.outcome is Outcome.CANCELLED
    assert cleanup.cancel_reason == "cleanup of fire_and_forget_cleanup#1 ran past cancel_grace"
    assert _warnings(caplog)[0].startswith(
        f"cleanup action rest#2 of fire_and_forget_cleanup#1 still running {GRACE:g} s after "
        "fire_and_forget_cleanup#1 was cancelled, at "
    )


@action
async def canceller(robot: Robot, target: ActionHandle[None]) -> None:
    target.cancel("second cancel from an action")
    me = current_action.get()
    assert me is not None


@pytest.mark.asyncio
async def test_a_second_cancel_from_another_action_keeps_the_first_reason() -> None:
    log: list[str] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = walk(robot, log)
        await robot.sleep(0.1)
        handle.cancel("first")
        await robot.sleep(0.1)
        await canceller(robot, handle)
        assert await handle.wait_done() is Outcome.CANCELLED
        await asyncio.sleep(0)
    assert handle.cancel_reason == "first"
    assert log == ["rested", "at rest"]


@action
async def quick_child(robot: Robot, log: list[str]) -> None:
    await robot.sleep(0)
    await robot.sleep(0)
    log.append("child done")


@action
async def cancel_self_then_spawn(robot: Robot, log: list[str]) -> None:
    me = current_action.get()
    assert me is not None
    me.cancel("myself")
    quick_child(robot, log)  # started after the cancel: it runs to its end
    # returns without awaiting: the cancellation arrives after the body is over


@pytest.mark.asyncio
async def test_a_cancel_arriving_after_the_body_ended_still_waits_for_the_children() -> None:
    log: list[str] = []
    async with Robot(cancel_grace=GRACE) as robot:
        handle = cancel_self_then_spawn(robot, log)
        assert await handle.wait_done() is Outcome.CANCELLED
        assert log == ["child done"]
        assert robot.handles() == []
