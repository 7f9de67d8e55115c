from __future__ import annotations

import asyncio
import copy
import dataclasses
import logging
import types
from collections.abc import Callable

import pytest

from log_support import logged
from pyrobots_aio import (
    ActionCancelled,
    ActionDefinitionError,
    ActionError,
    ActionHandle,
    ActionInfo,
    ActionState,
    EventKind,
    ExecEvent,
    GenericRobot,
    Outcome,
    PyRobotsError,
    Robot,
    TooManyActions,
    action,
)
from pyrobots_aio.testing import EventLog

pytestmark = pytest.mark.virtual_time


@action
async def forever(robot: Robot) -> None:
    await robot.sleep(3600)


@action
async def deaf(robot: Robot, release: asyncio.Event) -> None:
    """Ignores every cancellation until ``release`` is set."""
    while not release.is_set():
        try:
            await release.wait()
        except ActionCancelled:
            continue


@pytest.mark.asyncio
async def test_cancel_grace_warns_with_location_then_abandons(
    caplog: pytest.LogCaptureFixture,
) -> None:
    release = asyncio.Event()
    robot = Robot(cancel_grace=2.0)
    async with robot:
        t0 = robot.time()
        handle = deaf(robot, release)
        await robot.sleep(0.1)
    took = asyncio.get_running_loop().time() - t0
    await asyncio.sleep(0)
    assert took == pytest.approx(0.1 + 4.0)
    # Abandoned, its body was ended: no task is left behind, its outcome untouched.
    assert [t for t in asyncio.all_tasks() if t.get_name() == f"deaf#{handle.id}"] == []
    assert handle.outcome is Outcome.CANCELLED
    messages = [(r.levelno, r.getMessage()) for r in logged(caplog) if r.name.startswith("pyr")]
    assert messages[0][0] == logging.WARNING
    assert messages[0][1].startswith(
        f"action deaf#{handle.id} still running 2 s after cancellation, at "
    )
    assert "test_lifecycle.py:" in messages[0][1]
    assert messages[0][1].endswith("; cancelling it again")
    assert messages[1][0] == logging.ERROR
    assert messages[1][1].startswith(f"action deaf#{handle.id} ignored cancellation for 4 s, at ")


@action
async def slow_to_stop(robot: Robot, cleanup: float, log: list[tuple[str, float]]) -> None:
    try:
        await robot.sleep(3600)
    except ActionCancelled:
        await robot.sleep(cleanup)
        log.append(("action cleaned up", robot.time()))
        raise


@pytest.mark.asyncio
async def test_cancel_grace_cancels_a_slow_cleanup_again(caplog: pytest.LogCaptureFixture) -> None:
    """A cleanup that outlasts the grace is cancelled again at the grace, not abandoned later."""
    log: list[tuple[str, float]] = []
    async with Robot(cancel_grace=2.0) as robot:
        handle = slow_to_stop(robot, 10.0, log)
        await robot.sleep(0.5)
        handle.cancel("stop")
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.finished_at == 0.5 + 2.0
        assert handle.cancel_reason == "stop"
    assert log == []  # the cleanup's sleep was interrupted by the second cancellation
    assert [r.levelno for r in logged(caplog) if r.name.startswith("pyrobots_aio")] == [
        logging.WARNING
    ]


@pytest.mark.asyncio
async def test_no_watchdog_timer_outlives_the_robot(caplog: pytest.LogCaptureFixture) -> None:
    """Cancelling again re-arms the watchdog once: no stray timer fires after the robot stopped."""
    async with Robot(cancel_grace=2.0) as robot:
        handle = slow_to_stop(robot, 10.0, [])
        await robot.sleep(0.5)
        handle.cancel("stop")
        await handle.wait_done()
    await asyncio.sleep(10)  # past every deadline the watchdog ever had
    assert [(r.name, r.levelno) for r in logged(caplog, logging.WARNING)] == [
        ("pyrobots_aio.actions", logging.WARNING)
    ]


async def _cancel_during_shutdown(
    robot: Robot, start: Callable[[Robot], object], cancel_at: float
) -> float:
    """Run ``robot`` (``start`` it, leave at 0.5 s), cancel its task at ``cancel_at``: took."""

    async def main() -> None:
        async with robot:
            start(robot)
            await robot.sleep(0.5)

    loop = asyncio.get_running_loop()
    t0 = loop.time()
    task = asyncio.create_task(main())
    await asyncio.sleep(cancel_at)
    assert robot.is_running  # still shutting down
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert task.cancelled()
    assert not robot.is_running
    assert robot.handles() == []
    return loop.time() - t0


@pytest.mark.asyncio
async def test_cancelling_the_robot_task_during_shutdown_still_completes_it() -> None:
    log: list[tuple[str, float]] = []
    handles: list[ActionHandle[None]] = []
    robot = Robot()
    took = await _cancel_during_shutdown(
        robot, lambda robot: handles.append(slow_to_stop(robot, 1.0, log)), cancel_at=0.8
    )
    assert took == 1.5  # the action's whole 1 s cleanup, not cut short, not waited for beyond
    assert log == [("action cleaned up", 1.5)]
    (handle,) = handles
    assert handle.outcome is Outcome.CANCELLED
    assert handle.cancel_reason == "robot shutting down"


@pytest.mark.asyncio
async def test_cancelling_the_robot_task_while_monitors_stop_still_stops_actions() -> None:
    """Monitors stop first (their callback's cleanup takes 0.2 s), then actions (1 s)."""
    log: list[tuple[str, float]] = []
    handles: list[ActionHandle[None]] = []

    async def callback(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except asyncio.CancelledError:
            await robot.sleep(0.2)
            log.append(("callback cleaned up", robot.time()))
            raise

    def start(robot: Robot) -> None:
        robot.state.go = False
        robot.whenever("go", becomes=True).do(callback, robot)
        robot.state.go = True
        handles.append(slow_to_stop(robot, 1.0, log))

    robot = Robot()
    took = await _cancel_during_shutdown(robot, start, cancel_at=0.6)
    assert log == [("callback cleaned up", 0.7), ("action cleaned up", 1.7)]
    assert took == 1.7
    assert handles[0].outcome is Outcome.CANCELLED


@pytest.mark.asyncio
async def test_shutdown_is_bounded_when_the_robot_task_is_cancelled() -> None:
    release = asyncio.Event()
    robot = Robot(cancel_grace=0.5)
    loop = asyncio.get_running_loop()
    t0 = loop.time()
    try:
        with pytest.raises(TimeoutError):  # noqa: PT012 - the robot's lifetime is the point
            async with asyncio.timeout(1.0), robot:
                deaf(robot, release)
                forever(robot)
                await asyncio.sleep(3600)
        took = loop.time() - t0
    finally:
        release.set()
        await asyncio.sleep(0)
    assert took == pytest.approx(1.0 + 1.0)
    assert not robot.is_running
    assert robot.handles() == []


@pytest.mark.asyncio
async def test_leaving_the_robot_cancels_everything_and_leaves_no_task() -> None:
    before = asyncio.all_tasks()
    async with Robot() as robot:
        handles = [forever(robot) for _ in range(10)]
        await robot.sleep(0.1)
    assert all(h.outcome is Outcome.CANCELLED for h in handles)
    assert {h.cancel_reason for h in handles} == {"robot shutting down"}
    await asyncio.sleep(0)
    assert asyncio.all_tasks() - before == set()


@pytest.mark.asyncio
async def test_cancel_all_waits_for_every_action() -> None:
    async with Robot() as robot:
        handles = [forever(robot) for _ in range(100)]
        await robot.sleep(0.1)
        await robot.cancel_all("reset")
        assert all(h.done() and h.cancel_reason == "reset" for h in handles)
        assert robot.running() == []


@pytest.mark.asyncio
async def test_cancel_all_others_spares_the_caller_and_its_ancestors() -> None:
    @action
    async def emergency(robot: Robot) -> int:
        await robot.cancel_all_others("emergency stop")
        return len(robot.running())

    @action
    async def supervisor(robot: Robot) -> int:
        forever(robot)
        await robot.sleep(0.1)
        return await emergency(robot)

    async with Robot() as robot:
        others = [forever(robot) for _ in range(3)]
        await robot.sleep(0.05)
        assert await supervisor(robot) == 2  # supervisor and emergency themselves
        assert all(h.outcome is Outcome.CANCELLED for h in others)


@pytest.mark.asyncio
async def test_max_actions_raises_too_many_actions() -> None:
    async with Robot(max_actions=2) as robot:
        first, second = forever(robot), forever(robot)
        with pytest.raises(TooManyActions) as caught:
            forever(robot)
        assert caught.value.running == [first, second]
        assert str(caught.value) == (
            "cannot start 'forever': 2 actions already running (max_actions=2): "
            f"forever#{first.id}, forever#{second.id}; raise max_actions or cancel some"
        )
        first.cancel()
        await first.wait_done()
        third = forever(robot)
        assert not third.done()


def test_bad_robot_options_are_rejected() -> None:
    with pytest.raises(ValueError, match=r"max_actions must be a positive integer or None, got 0"):
        Robot(max_actions=0)
    with pytest.raises(ValueError, match=r"cancel_grace must be a positive number"):
        Robot(cancel_grace=-1)


@pytest.mark.asyncio
async def test_entering_a_running_robot_twice_is_an_error() -> None:
    async with Robot() as robot:
        with pytest.raises(PyRobotsError, match="is already running"):
            await robot.__aenter__()
    async with robot:  # and it can be started again afterwards
        assert robot.is_running


@pytest.mark.asyncio
async def test_introspection() -> None:
    @action
    async def parent(robot: Robot) -> None:
        forever(robot)
        await robot.sleep(3600)

    async with Robot() as robot:
        handle = parent(robot)
        await robot.sleep(1)
        infos = robot.running()
        assert [(i.name, i.parent, i.state) for i in infos] == [
            ("parent", None, ActionState.RUNNING),
            ("forever", handle.id, ActionState.RUNNING),
        ]
        assert infos[0].started_at == pytest.approx(robot.time() - 1)
        assert infos[0].location is not None
        assert "test_lifecycle.py:" in infos[0].location
        assert robot.actioninfo(handle.id) == infos[0]
        tree = robot.action_tree().splitlines()
        assert tree[0].startswith(f"parent#{handle.id} running at ")
        assert tree[1].startswith(f"  forever#{handle.id + 1} running at ")
        with pytest.raises(ActionError, match=r"no running action with id 999"):
            robot.actioninfo(999)
    assert robot.action_tree() == "(no running actions)"


class Pr2(GenericRobot):
    @action
    async def wave(self, times: int) -> str:
        await self.sleep(0.1)
        return f"waved {times} times" + (" (dummy)" if self.dummy else "")


@pytest.mark.asyncio
async def test_subclass_actions_bind_like_methods_and_dummy_flag() -> None:
    async with Pr2(dummy=True) as robot:
        assert await robot.wave(3) == "waved 3 times (dummy)"
    assert Robot is GenericRobot


@pytest.mark.asyncio
async def test_attach_actions_from_modules_and_functions() -> None:
    module = types.ModuleType("behaviours")

    @action
    async def greet(robot: Robot, name: str) -> str:
        return f"hello {name}"

    async def plain(robot: Robot) -> str:
        return "plain"

    module.greet = greet  # type: ignore[attr-defined]
    async with Robot(actions=[module, plain]) as robot:
        assert await robot.greet("ada") == "hello ada"
        assert await robot.plain() == "plain"
        with pytest.raises(AttributeError, match=r"attached actions: \['greet', 'plain'\]"):
            robot.nope  # noqa: B018
    with pytest.raises(ActionDefinitionError, match="module 'empty' defines no @action"):
        Robot(actions=[types.ModuleType("empty")])
    with pytest.raises(ActionDefinitionError, match="Robot already has that name"):
        Robot(actions=[action(sleep)])


async def sleep(robot: Robot) -> None:
    await robot.sleep(1)


class Recorder:
    def __init__(self) -> None:
        self.events: list[ExecEvent] = []

    def on_event(self, event: ExecEvent) -> None:
        self.events.append(event)


@pytest.mark.asyncio
async def test_instruments_see_every_action_event() -> None:
    recorder = Recorder()
    async with Robot(instruments=[recorder]) as robot:
        t0 = robot.time()
        handle = forever(robot)
        await robot.sleep(1)
        handle.cancel("bored")
        await handle.wait_done()
    assert [(e.kind, e.time - t0) for e in recorder.events] == [
        (EventKind.ACTION_SPAWNED, 0.0),
        (EventKind.ACTION_STARTED, 0.0),
        (EventKind.CANCEL_REQUESTED, 1.0),
        (EventKind.ACTION_FINISHED, 1.0),
    ]
    assert recorder.events[2].data == {"reason": "bored", "by": None}
    assert recorder.events[3].data == {"outcome": "cancelled", "error": None}
    assert {e.action for e in recorder.events} == {handle.id}


@pytest.mark.asyncio
async def test_a_snapshot_is_the_same_frozen_value_its_constructor_makes() -> None:
    async with Robot() as robot:
        handle = forever(robot)
        await robot.sleep(1)
        handle.cancel("enough")  # (a reason to copy; the snapshot is taken before it ends)
        info = ActionInfo.of(handle)
        built = ActionInfo(
            handle,
            handle.state,
            handle.started_at,
            handle.held,
            handle.awaiting,
            handle.cancel_reason,
        )
        assert info == built
        assert repr(info) == repr(built)
        assert (info.state, info.cancel_reason) == (ActionState.CANCELLING, "enough")
        assert info.location == built.location
        with pytest.raises(dataclasses.FrozenInstanceError):
            info.state = ActionState.DONE  # type: ignore[misc]
        assert dataclasses.replace(info, held=("wheels",)).held == ("wheels",)
        assert copy.copy(info) == info
        await handle.wait_done()


@pytest.mark.asyncio
async def test_an_action_waiting_for_a_lock_reports_where_it_is_defined() -> None:
    from pyrobots_aio import Resource, lock

    arm = Resource("arm")

    @action
    @lock(arm)
    async def wave(robot: Robot) -> None:
        await robot.sleep(1)

    async with Robot() as robot:
        first, second = wave(robot), wave(robot)
        await robot.sleep(0.5)
        info = robot.actioninfo(second.id)
        assert info.state is ActionState.WAITING
        assert info.awaiting == ("arm",)
        line = wave.fn.__wrapped__.__code__.co_firstlineno  # type: ignore[attr-defined]
        assert info.location is not None
        assert info.location.endswith(f"test_lifecycle.py:{line}")
        await first
        await second


@pytest.mark.asyncio
async def test_the_watchdog_keeps_each_deadline_when_cancellations_overlap() -> None:
    release = asyncio.Event()
    log = EventLog()
    try:
        async with Robot(cancel_grace=2.0, instruments=[log]) as robot:
            t0 = robot.time()
            first, second = deaf(robot, release), deaf(robot, release)
            await robot.sleep(1.0)
            first.cancel("first")
            await robot.sleep(1.0)
            second.cancel("second")
            await first.wait_done()
            await second.wait_done()
    finally:
        release.set()
        await asyncio.sleep(0)
    escalated = [(e.action, e.time - t0) for e in log.of_kind(EventKind.CANCEL_ESCALATED)]
    abandoned = [(e.action, e.time - t0) for e in log.of_kind(EventKind.ACTION_ABANDONED)]
    assert escalated == [(first.id, 3.0), (second.id, 4.0)]
    assert abandoned == [(first.id, 5.0), (second.id, 6.0)]
