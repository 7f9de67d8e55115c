from __future__ import annotations

import asyncio
import logging

import pytest

from log_support import logged
from pyrobots_aio import (
    ActionCancelled,
    ActionInterrupted,
    Outcome,
    Robot,
    action,
)


class Walker(Robot):
    """The pyRobots safe_walk listing's robot, recording what happens."""

    def __init__(self) -> None:
        super().__init__()
        self.log: list[tuple[float, str]] = []

    def note(self, what: str) -> None:
        self.log.append((self.time(), what))

    @action
    async def walk(self, speed: float) -> None:
        self.note(f"walk {speed}")
        try:
            await self.sleep(3600)
        finally:
            self.note("walk stopped")

    @action
    async def go_back_to_rest_pose(self) -> str:
        self.note("rest start")
        await self.sleep(0.5)
        self.note("rest done")
        return "rest"


pytestmark = pytest.mark.virtual_time


@action
async def safe_walk(robot: Walker, speed: float = 0.2) -> None:
    try:
        await robot.walk(speed)
    except ActionCancelled:
        await robot.go_back_to_rest_pose()
        robot.note("cleanup done")
        raise


@pytest.mark.asyncio
async def test_safe_walk_listing() -> None:
    async with Walker() as robot:
        t0 = robot.time()
        handle = safe_walk(robot, 0.3)
        await robot.sleep(1.0)
        handle.cancel("stop")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert [what for _, what in robot.log] == [
            "walk 0.3",
            "walk stopped",
            "rest start",
            "rest done",
            "cleanup done",
        ]
        times = {what: t - t0 for t, what in robot.log}
        assert times["walk stopped"] == pytest.approx(1.0)
        assert times["rest done"] == pytest.approx(1.5)
        assert handle.finished_at is not None
        assert handle.finished_at - t0 == pytest.approx(1.5)


@pytest.mark.asyncio
async def test_children_and_parents() -> None:
    async with Walker() as robot:
        seen = {}

        @action
        async def parent(robot: Walker) -> None:
            child = robot.walk(0.1)
            await asyncio.sleep(0)
            seen["child"] = child
            seen["children"] = this.children
            await robot.sleep(1)

        this = parent(robot)
        await robot.sleep(0.5)
        child = seen["child"]
        assert child.parent is this
        assert child.childof(this)
        assert not this.childof(child)
        assert seen["children"] == (child,)
        assert this.parent is None
        await this
        assert child.outcome is Outcome.CANCELLED
        assert child.cancel_reason == f"its parent parent#{this.id} finished"
        assert this.children == ()


@pytest.mark.asyncio
async def test_childof_is_true_only_for_ancestors() -> None:
    @action
    async def tree(robot: Robot, depth: int, width: int) -> None:
        for _ in range(width):
            if depth:
                tree(robot, depth - 1, width)
        await robot.sleep(3600)

    async with Robot() as robot:
        first, second = tree(robot, 2, 2), tree(robot, 1, 1)
        await robot.sleep(1)
        left, right = first.children
        (grandchild, _) = left.children
        (other,) = second.children
        assert grandchild.childof(left)
        assert grandchild.childof(first)
        assert left.childof(first)
        assert not left.childof(right)  # siblings
        assert not right.childof(left)
        assert not grandchild.childof(right)  # a cousin's child
        assert not other.childof(first)  # has a parent, but an unrelated one
        assert not grandchild.childof(second)
        assert not grandchild.childof(grandchild)
        assert not first.childof(grandchild)
        await robot.cancel_all()


@pytest.mark.asyncio
async def test_parent_is_done_only_after_its_children() -> None:
    order = []

    @action
    async def slow_cleanup(robot: Robot, name: str) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await robot.sleep(0.3)
            order.append(name)
            raise

    @action
    async def parent(robot: Robot) -> str:
        slow_cleanup(robot, "a")
        slow_cleanup(robot, "b")
        await robot.sleep(0.1)
        return "parent body over"

    async with Robot() as robot:
        handle = parent(robot)
        assert await handle == "parent body over"
        assert order == ["a", "b"]
        assert robot.handles() == []


@pytest.mark.asyncio
async def test_cancelling_a_parent_cancels_its_whole_subtree() -> None:
    """Every descendant is cancelled at once with the canceller's reason, not reaped later."""
    cleaned: list[tuple[str, float]] = []
    cleanup = {"top": 0.05, "middle": 0.0, "child": 0.2, "grandchild": 0.1}

    async def clean_up(robot: Robot, name: str) -> None:
        cleaned.append((name, robot.time()))
        await robot.sleep(cleanup[name])

    @action
    async def leaf(robot: Robot, name: str) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await clean_up(robot, name)
            raise

    @action
    async def middle(robot: Robot) -> None:
        leaf(robot, "grandchild")
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await clean_up(robot, "middle")
            raise

    @action
    async def top(robot: Robot) -> None:
        middle(robot)
        try:
            await leaf(robot, "child")
        except ActionCancelled:
            await clean_up(robot, "top")
            raise

    async with Robot() as robot:
        handle = top(robot)
        await robot.sleep(1)
        t_cancel = robot.time()
        subtree = dict(zip(["top", "middle", "child", "grandchild"], robot.handles(), strict=True))
        assert [(h.name, h.parent) for h in subtree.values()] == [
            ("top", None),
            ("middle", handle),
            ("leaf", handle),
            ("leaf", subtree["middle"]),
        ]
        done: list[str] = []
        for name, h in subtree.items():
            h.add_done_callback(lambda _h, name=name: done.append(name))
        handle.cancel("abort")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert sorted(cleaned, key=lambda c: c[0]) == [
            ("child", t_cancel),
            ("grandchild", t_cancel),
            ("middle", t_cancel),
            ("top", t_cancel),
        ]
        assert {name: h.cancel_reason for name, h in subtree.items()} == dict.fromkeys(
            subtree, "abort"
        )
        assert all(h.outcome is Outcome.CANCELLED for h in subtree.values())
        # Descendants are done before their ancestors; a parent waits for its children's cleanup.
        assert done == ["grandchild", "middle", "child", "top"]
        assert {name: h.finished_at for name, h in subtree.items()} == pytest.approx(
            {
                "top": t_cancel + 0.2,
                "middle": t_cancel + 0.1,
                "child": t_cancel + 0.2,
                "grandchild": t_cancel + 0.1,
            }
        )
        assert robot.running() == []


@pytest.mark.asyncio
async def test_parent_catches_interrupted_child_and_carries_on() -> None:
    """The random-walk bug: a reflex cancels the current motion; the walk goes on."""
    steps = []

    @action
    async def drive(robot: Robot, step: int) -> None:
        await robot.sleep(1.0)
        steps.append(step)

    @action
    async def random_walk(robot: Robot) -> str:
        interrupted = 0
        for step in range(5):
            try:
                await drive(robot, step)
            except ActionInterrupted:
                interrupted += 1
        return f"walk over, {interrupted} interrupted"

    async with Robot() as robot:
        walk = random_walk(robot)
        await robot.sleep(1.5)
        (current,) = walk.children
        current.cancel("bumper")
        assert await walk == "walk over, 1 interrupted"
        assert steps == [0, 2, 3, 4]
        assert walk.outcome is Outcome.SUCCEEDED


@pytest.mark.asyncio
async def test_failure_is_isolated_and_logged_when_nobody_waits(
    caplog: pytest.LogCaptureFixture,
) -> None:
    @action
    async def broken(robot: Robot) -> None:
        raise RuntimeError("sensor unplugged")

    @action
    async def sibling(robot: Robot) -> str:
        await robot.sleep(1)
        return "fine"

    @action
    async def parent(robot: Robot) -> str:
        broken(robot)
        return await sibling(robot)

    async with Robot() as robot:
        assert await parent(robot) == "fine"
    records = [r for r in caplog.records if r.name == "pyrobots_aio.actions"]
    assert [r.getMessage().splitlines()[0] for r in records] == [
        "action broken#2 failed and nobody retrieved its error:"
    ]
    assert records[0].levelno == logging.ERROR
    report = records[0].getMessage().splitlines()
    assert report[1] == "Traceback (most recent call last):"
    assert report[-1] == "RuntimeError: sensor unplugged"


@pytest.mark.asyncio
async def test_awaited_failure_is_not_logged(caplog: pytest.LogCaptureFixture) -> None:
    @action
    async def broken(robot: Robot) -> None:
        await robot.sleep(0.1)
        raise RuntimeError("sensor unplugged")

    async with Robot() as robot:
        with pytest.raises(RuntimeError):
            await broken(robot)
    assert "nobody is waiting" not in caplog.text


@pytest.mark.asyncio
async def test_cleanup_started_after_cancel_runs_normally() -> None:
    @action
    async def rest(robot: Robot) -> str:
        await robot.sleep(0.2)
        return "rest"

    results = []

    @action
    async def worker(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            results.append(await rest(robot))
            raise

    async with Robot() as robot:
        handle = worker(robot)
        await robot.sleep(0.1)
        handle.cancel()
        await handle.wait_done()
        assert results == ["rest"]


@pytest.mark.asyncio
async def test_a_parent_waiting_for_its_slow_cleanup_child_is_not_abandoned(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The cleanup child is itself cancelled at the parent's grace and re-cancelled at its own.

    The parent is not ignoring cancellation, it waits for a child that is bounded: it is
    done when the child is, never before (and never abandoned, nor its task left behind).
    """

    @action
    async def rest(robot: Robot) -> None:
        try:
            await robot.sleep(5)
        except ActionCancelled:
            await robot.sleep(3)
            raise

    @action
    async def walk(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            await rest(robot)
            raise

    async with Robot(cancel_grace=2.0) as robot:
        handle = walk(robot)
        await robot.sleep(1)
        handle.cancel("stop")
        await robot.sleep(0.5)
        (child,) = handle.children
        assert await handle.wait_done() is Outcome.CANCELLED
        assert child.done()
        assert child.cancel_reason == "the task awaiting it was cancelled"
        assert (handle.finished_at, child.finished_at) == (1 + 2 + 2, 1 + 2 + 2)
    assert [r.levelno for r in logged(caplog) if r.name.startswith("pyrobots_aio")] == [
        logging.WARNING,  # walk cancelled again at 3 s
        logging.WARNING,  # rest cancelled again at 5 s
    ]
