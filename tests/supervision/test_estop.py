"""robot.emergency_stop: latched, immediate, above every priority, never refused."""

from __future__ import annotations

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionInterrupted,
    CompoundResource,
    EventKind,
    Outcome,
    Resource,
    Robot,
    RobotNotRunningError,
    TooManyActions,
    action,
    lock,
)
from pyrobots_aio.testing import EventLog

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

ARM, HEAD, WHEELS = Resource("arm"), Resource("head"), Resource("wheels")
BODY = CompoundResource(ARM, HEAD, name="body")


class Arm(Robot):
    """A robot whose actuators note when they were halted, and whose actions note their cleanup."""

    def __init__(self, **options: object) -> None:
        self.record = EventLog()
        super().__init__(instruments=[self.record], **options)  # type: ignore[arg-type]
        self.notes: list[tuple[float, str]] = []

    def note(self, what: str) -> None:
        self.notes.append((self.time(), what))

    def halt_actuators(self) -> None:
        self.note("halted")
        super().halt_actuators()

    @action
    @lock(ARM, priority=1000)
    async def wave(self) -> None:
        try:
            await self.sleep(3600)
        except ActionCancelled:
            await self.sleep(0.5)  # lowering the arm takes a while
            self.note("arm lowered")
            raise

    @action
    @lock(BODY)
    async def bow(self) -> None:
        await self.sleep(3600)

    @action
    @lock(WHEELS)
    async def patrol(self) -> None:
        await self.step()

    @action
    @lock(WHEELS)
    async def step(self) -> None:
        await self.sleep(3600)

    @action
    async def think(self) -> str:
        await self.sleep(10)
        return "thought"


async def test_it_preempts_every_holder_and_waiter_whatever_its_priority() -> None:
    async with Arm() as robot:
        wave, patrol, think = robot.wave(), robot.patrol(), robot.think()
        await robot.sleep(1)
        bow = robot.bow()  # waits for the arm, which wave holds
        await robot.sleep(1)
        (step,) = patrol.children
        stop = robot.emergency_stop("operator")
        assert robot.notes == [(2.0, "halted")]  # at the call, before anything else runs
        assert robot.emergency_stopped
        assert robot.emergency_stop_reason == "operator"
        assert (robot.state.emergency_stop, robot.state.emergency_stop_reason) == (True, "operator")
        await stop
        assert robot.time() == 2.5  # once wave's cleanup is over
        assert robot.notes[-1] == (2.5, "arm lowered")
        for handle in (wave, patrol, step, bow):
            assert handle.outcome is Outcome.CANCELLED
            assert handle.cancel_reason == "emergency stop: operator"
            error = handle.exception()
            assert isinstance(error, ActionInterrupted)
            assert error.by is stop
        assert not think.done()  # it holds nothing: the emergency stop leaves it alone
        assert robot.resources.held() == {}
        assert await think == "thought"
        log = robot.record
        assert stop.parent is None
        assert log.outcomes("emergency_stop") == ["succeeded"]
        cancels = [(e.name, e.time, e.data["by"]) for e in log.of_kind(EventKind.CANCEL_REQUESTED)]
        assert sorted(cancels) == sorted(
            (name, 2.0, stop.id) for name in ("wave", "patrol", "step", "bow")
        )


async def test_it_is_never_refused_at_max_actions() -> None:
    async with Arm(max_actions=3) as robot:
        wave, patrol = robot.wave(), robot.patrol()  # and patrol's step: three
        await robot.sleep(1)
        with pytest.raises(TooManyActions):
            robot.think()
        stop = robot.emergency_stop("cap reached")
        assert stop.outcome is Outcome.NOT_DONE
        await stop
        assert wave.cancelled()
        assert patrol.cancelled()


async def test_an_action_holding_a_resource_that_calls_it_is_stopped_too() -> None:
    @action
    @lock(WHEELS)
    async def reflex(robot: Robot) -> None:
        robot.emergency_stop("cliff")
        await robot.sleep(3600)

    async with Robot() as robot:
        handle = reflex(robot)
        assert await handle.wait_done() is Outcome.CANCELLED
        assert handle.cancel_reason == "emergency stop: cliff"
        (stop,) = (h for h in robot.handles() if h.name == "emergency_stop")
        assert stop.parent is None  # the root scope: cancelling the caller spares it
        await stop
        assert stop.outcome is Outcome.SUCCEEDED


async def test_it_latches_the_first_reason_until_cleared() -> None:
    async with Arm() as robot:
        await robot.emergency_stop("first")
        wave = robot.wave()  # a new holder while latched: only motion is refused
        await robot.sleep(1)
        await robot.emergency_stop("second")
        assert wave.cancel_reason == "emergency stop: second"
        assert robot.emergency_stop_reason == "first"
        robot.clear_emergency_stop()
        assert not robot.emergency_stopped
        assert (robot.state.emergency_stop, robot.state.emergency_stop_reason) == (False, None)
        robot.clear_emergency_stop()  # clearing twice does nothing
        assert robot.state.version("emergency_stop") == 2


async def test_it_can_be_started_from_any_event() -> None:
    async with Arm() as robot:
        robot.state.cliff_front_left = False
        robot.whenever("cliff_front_left", becomes=True).do(robot.emergency_stop, "cliff")
        wave = robot.wave()
        await robot.sleep(1)
        robot.state.cliff_front_left = True
        assert await wave.wait_done() is Outcome.CANCELLED
        assert wave.cancel_reason == "emergency stop: cliff"
        assert robot.notes[0] == (1.0, "halted")
        assert robot.emergency_stop_reason == "cliff"


async def test_it_needs_a_running_robot() -> None:
    robot = Robot()
    with pytest.raises(RobotNotRunningError, match="is not running"):
        robot.emergency_stop("too early")
    assert not robot.emergency_stopped


async def test_during_shutdown_it_still_stops_then_says_the_robot_is_shutting_down() -> None:
    seen: list[str] = []

    @action
    async def supervisor(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:  # the robot's exit: stop everything on the way out
            try:
                robot.emergency_stop("leaving")
            except RobotNotRunningError as error:
                seen.append(str(error))
            raise

    async with Arm() as robot:
        wave = robot.wave()
        supervisor(robot)
        await robot.sleep(1)
    assert robot.emergency_stop_reason == "leaving"
    assert robot.notes[0] == (1.0, "halted")
    assert wave.cancelled()
    assert seen == [
        "cannot start action 'emergency_stop': <Arm running> is shutting down; start it "
        "before leaving 'async with robot:', or from an action's cleanup"
    ]
