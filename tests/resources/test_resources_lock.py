"""``lock`` as a decorator (both orders, stacked) and as a context manager, on real robots."""

from __future__ import annotations

import asyncio
import functools
import inspect
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

import pytest

from pyrobots_aio import (
    ActionCancelled,
    ActionSkipped,
    ActionState,
    InvalidResourceError,
    LockUsageError,
    Outcome,
    Robot,
    action,
)
from pyrobots_aio.actions import current_action, lock
from pyrobots_aio.resources import CompoundResource, Resource

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

P = ParamSpec("P")
T = TypeVar("T")
L_ARM, R_ARM = Resource("l_arm"), Resource("r_arm")
ARMS = CompoundResource(L_ARM, R_ARM, name="arms")
WHEELS = Resource("wheels")


class Arms(Robot):
    """The pyRobots resources listing's robot; it notes what its actions do."""

    def __init__(self) -> None:
        super().__init__()
        self.log: list[str] = []
        self.gate = asyncio.Event()


@action
@lock(ARMS)
async def lift_box(robot: Arms) -> str:
    robot.log.append("lift start")
    await robot.gate.wait()
    robot.log.append("lift end")
    return "lifted"


@lock(L_ARM)
@action
async def wave_hand(robot: Arms) -> str:
    robot.log.append("wave")
    return "waved"


@action
@lock(L_ARM, wait=False)
async def scratch_head(robot: Arms) -> str:
    robot.log.append("scratch")
    return "scratched"


async def settle() -> None:
    for _ in range(3):
        await asyncio.sleep(0)


@pytest.mark.asyncio
async def test_lift_box_wave_hand_scratch_head_listing() -> None:
    async with Arms() as robot:
        lift = lift_box(robot)
        await settle()
        wave = wave_hand(robot)
        scratch = scratch_head(robot)
        await settle()
        assert robot.resources.owner(ARMS) is lift
        assert robot.resources.waiters(L_ARM) == [wave]
        assert scratch.outcome is Outcome.SKIPPED
        with pytest.raises(ActionSkipped) as info:
            await scratch
        assert str(info.value) == f"skipped: resource 'l_arm' is busy (held by lift_box#{lift.id})"
        assert info.value.resource == L_ARM
        assert info.value.holder is lift
        assert info.value.handle is scratch
        robot.gate.set()
        assert await wave == "waved"
        assert await lift == "lifted"
        assert robot.log == ["lift start", "lift end", "wave"]
        assert repr(robot.resources) == "<ResourceManager idle>"


@pytest.mark.asyncio
async def test_held_and_awaiting_show_in_introspection() -> None:
    async with Arms() as robot:
        lift = lift_box(robot)
        await settle()
        wave = wave_hand(robot)
        await settle()
        infos = {info.id: info for info in robot.running()}
        assert infos[lift.id].held == ("arms",)
        assert infos[lift.id].state is ActionState.RUNNING
        assert infos[wave.id].awaiting == ("l_arm",)
        assert infos[wave.id].held == ()
        assert wave.state is ActionState.WAITING
        line = robot.action_tree().splitlines()[1]
        assert line.startswith(f"wave_hand#{wave.id} waiting waits for l_arm at ")
        defined_at = inspect.getsourcelines(wave_hand.fn)[1]  # its first decorator's line
        assert line.endswith(f"test_resources_lock.py:{defined_at}")  # where it is defined
        robot.gate.set()
        await wave
        assert wave.held == ()
        assert wave.awaiting == ()


def test_decorators_keep_names_in_both_orders() -> None:
    assert lift_box.name == "lift_box"
    assert wave_hand.name == "wave_hand"
    assert wave_hand.__name__ == "wave_hand"
    assert lift_box.fn.__name__ == "lift_box"
    assert repr(wave_hand) == "<action wave_hand>"


class Rover(Robot):
    """Locked actions as methods, in both decorator orders."""

    @lock(WHEELS)
    @action
    async def forward(self) -> tuple[str, ...]:
        me = current_action.get()
        assert me is not None
        return me.held

    @action
    @lock(WHEELS, priority=3)
    async def backward(self, distance: float) -> float:
        await asyncio.sleep(0)
        return -distance


@pytest.mark.asyncio
async def test_locked_methods_bind_like_methods() -> None:
    async with Rover() as robot:
        assert await robot.forward() == ("wheels",)
        assert await robot.backward(2.0) == -2.0
        assert robot.resources.held() == {}


@action
@lock(L_ARM)
@lock(WHEELS)
async def stacked(robot: Robot) -> tuple[str, ...]:
    me = current_action.get()
    assert me is not None
    return me.held


@lock(WHEELS)
@action
@lock(R_ARM)
async def stacked_around(robot: Robot) -> tuple[str, ...]:
    me = current_action.get()
    assert me is not None
    return me.held


@pytest.mark.asyncio
async def test_stacked_locks_make_one_atomic_request() -> None:
    async with Robot() as robot:
        assert await stacked(robot) == ("l_arm", "wheels")
        assert await stacked_around(robot) == ("wheels", "r_arm")


@action
async def hold(robot: Robot, resource: Resource, gate: asyncio.Event) -> None:
    async with lock(resource):
        await gate.wait()


@pytest.mark.asyncio
async def test_stacked_request_waits_for_all_without_holding_any() -> None:
    gate = asyncio.Event()
    async with Robot() as robot:
        holder = hold(robot, WHEELS, gate)
        await settle()
        both = stacked(robot)
        await settle()
        assert both.awaiting == ("l_arm", "wheels")
        assert robot.resources.owner(L_ARM) is None  # no hold-and-wait
        assert robot.resources.owner(WHEELS) is holder
        gate.set()
        assert await both == ("l_arm", "wheels")


def test_stacked_locks_with_different_options_are_refused() -> None:
    with pytest.raises(LockUsageError) as info:

        @lock(L_ARM, priority=2)
        @lock(WHEELS)
        async def confused(robot: Robot) -> None: ...

    assert str(info.value) == (
        "stacked @lock decorators on 'confused' take their resources in one atomic request, "
        "so they need the same wait/priority/preempt: lock(Resource('l_arm'), wait=True, "
        "priority=2, preempt=False) differs from the lock on 'wheels'; give them the same options"
    )


@action
async def drive_block(robot: Robot, inside: asyncio.Event, gate: asyncio.Event) -> str:
    me = current_action.get()
    assert me is not None
    async with lock(WHEELS) as grant:
        assert grant.held
        assert me.held == ("wheels",)
        async with lock(WHEELS):  # the same action may take it again
            assert robot.resources.owner(WHEELS) is me
        inside.set()
        await gate.wait()
    assert me.held == ()
    assert robot.resources.owner(WHEELS) is None
    await gate.wait()
    return "done"


@pytest.mark.asyncio
async def test_context_manager_holds_for_the_block() -> None:
    inside, gate = asyncio.Event(), asyncio.Event()
    async with Robot() as robot:
        handle = drive_block(robot, inside, gate)
        await inside.wait()
        assert robot.resources.owner(WHEELS) is handle
        gate.set()
        assert await handle == "done"


SHARED = lock(WHEELS)


@action
async def take_shared(robot: Robot, log: list[str], tag: str) -> None:
    async with SHARED:
        log.append(f"{tag} in")
        await asyncio.sleep(0)
        log.append(f"{tag} out")


@pytest.mark.asyncio
async def test_one_lock_object_shared_by_concurrent_actions() -> None:
    log: list[str] = []
    async with Robot() as robot:
        await asyncio.gather(*(take_shared(robot, log, t).wait() for t in "abc"))
    assert log == ["a in", "a out", "b in", "b out", "c in", "c out"]


@action
@lock(WHEELS)
async def parent_drives(robot: Robot, go: asyncio.Event, seen: list[object]) -> None:
    await go.wait()
    await child_drives(robot, seen)


@action
@lock(WHEELS)
async def child_drives(robot: Robot, seen: list[object]) -> None:
    seen.append(robot.resources.owner(WHEELS))
    seen.append(current_action.get())


@pytest.mark.asyncio
async def test_child_action_takes_its_parents_resource_without_waiting() -> None:
    seen: list[object] = []
    go, gate = asyncio.Event(), asyncio.Event()
    async with Robot() as robot:
        parent = parent_drives(robot, go, seen)
        await settle()
        stranger = hold(robot, WHEELS, gate)
        await settle()
        assert robot.resources.waiters(WHEELS) == [stranger]
        go.set()  # the child asks after the stranger, and goes first all the same
        await parent
        child = seen[1]
        assert seen == [child, child]
        assert child is not parent
        assert robot.resources.owner(WHEELS) is stranger
        gate.set()
        await stranger


@action
async def uses_helper(robot: Robot, log: list[str]) -> None:
    me = current_action.get()
    assert me is not None
    await lock(WHEELS)(busy_child)(robot, asyncio.Event(), log)
    log.append(f"after the call it holds {me.held}")


async def busy_child(robot: Robot, started: asyncio.Event, log: list[str]) -> None:
    log.append(f"helper holds {robot.resources.owner(WHEELS) is current_action.get()}")


@pytest.mark.asyncio
async def test_locked_helper_inside_an_action_holds_for_the_call() -> None:
    log: list[str] = []
    async with Robot() as robot:
        await uses_helper(robot, log)
        assert log == ["helper holds True", "after the call it holds ()"]
        assert robot.resources.held() == {}


@action
@lock(WHEELS)
async def finishes_before_child(robot: Robot, stopped: list[object]) -> None:
    unlocked_child(robot, stopped)
    await asyncio.sleep(0)


@action
async def unlocked_child(robot: Robot, stopped: list[object]) -> None:
    try:
        await asyncio.sleep(3600)
    finally:
        await asyncio.sleep(0)  # its cleanup still drives the wheels its parent locked
        stopped.append(robot.resources.owner(WHEELS))


@pytest.mark.asyncio
async def test_decorator_holds_until_the_action_is_done_children_included() -> None:
    stopped: list[object] = []
    async with Robot() as robot:
        parent = finishes_before_child(robot, stopped)
        await parent
        assert stopped == [parent]
        assert robot.resources.owner(WHEELS) is None


@action
@lock(WHEELS)
async def crash(robot: Robot) -> None:
    await asyncio.sleep(0)
    raise RuntimeError("motor stalled")


@pytest.mark.asyncio
async def test_failure_releases() -> None:
    async with Robot() as robot:
        broken = crash(robot)
        after = child_drives(robot, [])
        with pytest.raises(RuntimeError, match="motor stalled"):
            await broken
        assert await after.wait_done() is Outcome.SUCCEEDED
        assert robot.resources.held() == {}


@pytest.mark.asyncio
async def test_cancel_while_waiting_leaves_nothing_queued() -> None:
    gate = asyncio.Event()
    async with Arms() as robot:
        holder = hold(robot, L_ARM, gate)
        await settle()
        waiting = wave_hand(robot)
        await settle()
        assert robot.resources.waiters(L_ARM) == [waiting]
        waiting.cancel("changed my mind")
        assert await waiting.wait_done() is Outcome.CANCELLED
        assert robot.resources.waiters(L_ARM) == []
        assert robot.log == []
        gate.set()
        await holder
        assert repr(robot.resources) == "<ResourceManager idle>"


@action
@lock(WHEELS)
async def stubborn(robot: Robot, log: list[str]) -> None:
    try:
        await asyncio.sleep(3600)
    except ActionCancelled:
        log.append(f"cleanup holds {robot.resources.owner(WHEELS) is current_action.get()}")
        raise


@pytest.mark.asyncio
async def test_robot_shutdown_releases_holders_and_waiters() -> None:
    log: list[str] = []
    robot = Robot()
    async with robot:
        first = stubborn(robot, log)
        second = stubborn(robot, log)
        await settle()
        assert robot.resources.waiters(WHEELS) == [second]
    assert first.outcome is Outcome.CANCELLED
    assert second.outcome is Outcome.CANCELLED
    assert log == ["cleanup holds True"]
    assert repr(robot.resources) == "<ResourceManager idle>"


@pytest.mark.asyncio
async def test_two_robots_never_share_locks() -> None:
    gate = asyncio.Event()
    async with Robot() as one, Robot() as two:
        a = hold(one, WHEELS, gate)
        b = hold(two, WHEELS, gate)
        await settle()
        assert one.resources.owner(WHEELS) is a
        assert two.resources.owner(WHEELS) is b
        assert one.resources.waiters(WHEELS) == []
        gate.set()


def test_locking_something_that_is_not_a_resource() -> None:
    with pytest.raises(InvalidResourceError) as info:
        lock("wheels")  # type: ignore[arg-type]
    assert str(info.value) == (
        "'wheels' is not a resource (needed as the resource to lock); "
        "declare it as Resource('wheels') or CompoundResource(...)"
    )


def test_bare_lock_without_a_resource_says_to_name_one() -> None:
    async def drive(robot: Robot) -> None: ...

    with pytest.raises(InvalidResourceError) as info:
        lock(drive)  # type: ignore[arg-type]
    assert str(info.value) == (
        "lock() got the function 'drive' instead of a resource: a bare @lock names nothing "
        "to take; write @lock(RESOURCE), e.g. @lock(Resource('wheels'))"
    )
    with pytest.raises(InvalidResourceError) as info:
        lock(lift_box)  # type: ignore[arg-type]
    assert str(info.value).startswith("lock() got the function 'lift_box' instead of a resource")


def test_plain_with_says_to_use_async_with() -> None:
    wheels = lock(WHEELS)
    expected = (
        "'with lock(Resource('wheels'), wait=True, priority=0, preempt=False)' cannot wait for "
        "the resource without blocking the loop; write 'async with lock(Resource('wheels'), "
        "wait=True, priority=0, preempt=False):' inside an @action body"
    )
    with pytest.raises(LockUsageError) as info, wheels:
        pass
    assert str(info.value) == expected
    with pytest.raises(LockUsageError) as info:
        wheels.__exit__(None, None, None)
    assert str(info.value) == expected


def test_invalid_options() -> None:
    with pytest.raises(LockUsageError) as info:
        lock(WHEELS, priority="high")  # type: ignore[arg-type]
    assert str(info.value) == (
        "priority must be an int, got 'high'; e.g. priority=10 (higher goes first)"
    )
    with pytest.raises(
        LockUsageError, match=r"^preempt must be True, False or 'suspend', got 'yes'$"
    ):
        lock(WHEELS, preempt="yes")  # type: ignore[arg-type]


def test_decorating_something_that_is_not_async() -> None:
    def plain(robot: Robot) -> None: ...

    with pytest.raises(LockUsageError) as info:
        lock(WHEELS)(plain)  # type: ignore[arg-type]
    assert str(info.value).startswith(
        "lock(Resource('wheels'), wait=True, priority=0, preempt=False) decorates an "
        "'async def' or an @action, got <function "
    )


@pytest.mark.asyncio
async def test_context_manager_outside_an_action() -> None:
    with pytest.raises(LockUsageError) as info:
        async with lock(WHEELS):
            pass
    assert str(info.value) == (
        "'async with lock(Resource('wheels'), wait=True, priority=0, preempt=False)' needs a "
        "running action to hold the resource; use it inside an @action body"
    )


@pytest.mark.asyncio
async def test_locked_function_outside_an_action() -> None:
    async with Robot() as robot:
        with pytest.raises(LockUsageError) as info:
            await lock(WHEELS)(busy_child)(robot, asyncio.Event(), [])
    assert str(info.value) == (
        "@lock on 'busy_child' needs to run inside an action; put @action on it and "
        "start it as busy_child(robot, ...)"
    )


@action
async def misplaced(robot: Robot) -> None:
    await lock(WHEELS)(busy_child)("not a robot", asyncio.Event(), [])  # type: ignore[arg-type]


@pytest.mark.asyncio
async def test_locked_function_needs_the_robot_first() -> None:
    async with Robot() as robot:
        with pytest.raises(LockUsageError) as info:
            await misplaced(robot)
    assert str(info.value) == (
        "@lock on 'busy_child' (its first argument) needs a robot with .resources "
        "(a ResourceManager), got 'not a robot'"
    )


Y = Resource("y")
XY = CompoundResource(Resource("x"), Y, name="xy")


@action
async def streamer(robot: Robot, log: list[str], tag: str, rounds: int) -> None:
    for _ in range(rounds):
        async with lock(Y):
            log.append(tag)
            await asyncio.sleep(0)


@action
@lock(XY)
async def compound(robot: Robot, log: list[str]) -> None:
    log.append("xy")


@pytest.mark.asyncio
async def test_compound_request_is_not_starved_by_a_stream_of_single_requests() -> None:
    log: list[str] = []
    async with Robot() as robot:
        streams = [streamer(robot, log, tag, 50) for tag in "ab"]
        for _ in range(10):
            await asyncio.sleep(0)
        both = compound(robot, log)
        await asyncio.sleep(0)
        assert both.awaiting == ("xy",)
        arrived = len(log)
        holder = robot.resources.owner(Y)
        assert holder in streams
        other = next(s for s in streams if s is not holder)
        assert robot.resources.waiters(Y) == [other, both]
        await both
        # the other streamer, queued first, has its turn; then xy, before the holder again
        tag = "a" if other is streams[0] else "b"
        assert log[arrived : arrived + 2] == [tag, "xy"]
        for stream in streams:
            await stream
        assert log.count("a") == log.count("b") == 50


@pytest.mark.asyncio
async def test_a_skipped_child_fails_its_parent_and_keeps_its_own_handle() -> None:
    @action
    async def tries_to_scratch(robot: Arms) -> None:
        await scratch_head(robot)

    async with Arms() as robot:
        lift = lift_box(robot)
        await settle()
        parent = tries_to_scratch(robot)
        assert await parent.wait_done() is Outcome.FAILED  # it ran, and raised
        error = parent.exception()
        assert isinstance(error, ActionSkipped)
        assert error.handle is not parent
        assert error.handle.name == "scratch_head"
        assert error.handle.outcome is Outcome.SKIPPED
        assert error.holder is lift
        robot.gate.set()


# -- @lock under a user decorator: held until done if ``__wrapped__`` is kept --------


def passthrough(fn: Callable[P, Coroutine[Any, Any, T]]) -> Callable[P, Coroutine[Any, Any, T]]:
    """A user decorator that keeps ``__wrapped__`` (functools.wraps)."""

    @functools.wraps(fn)
    async def wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        return await fn(*args, **kwargs)

    return wrapper


def opaque(fn: Callable[P, Coroutine[Any, Any, T]]) -> Callable[P, Coroutine[Any, Any, T]]:
    """A user decorator that hides what it wraps (no functools.wraps)."""

    async def opaque_wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        return await fn(*args, **kwargs)

    return opaque_wrapper


@action
@passthrough
@lock(WHEELS)
async def decorated_parent(robot: Robot, stopped: list[object]) -> None:
    unlocked_child(robot, stopped)
    await asyncio.sleep(0)


@action
@opaque
@lock(WHEELS)
async def hidden_parent(robot: Robot, stopped: list[object]) -> None:
    unlocked_child(robot, stopped)
    await asyncio.sleep(0)


@pytest.mark.asyncio
async def test_a_wrapping_decorator_between_action_and_lock_still_holds_until_done() -> None:
    stopped: list[object] = []
    async with Robot() as robot:
        parent = decorated_parent(robot, stopped)
        await parent
        assert stopped == [parent]
        assert robot.resources.owner(WHEELS) is None


@pytest.mark.asyncio
async def test_a_decorator_hiding_the_lock_makes_it_hold_for_the_call_only() -> None:
    """The documented limit: without ``__wrapped__`` the lock is held like a helper's."""
    stopped: list[object] = []
    async with Robot() as robot:
        await hidden_parent(robot, stopped)
        assert stopped == [None]
        assert robot.resources.owner(WHEELS) is None


GRIPPER, CAMERA = Resource(), Resource()  # unnamed, as pyRobots lets you declare them


@action
@lock(GRIPPER)
async def grip(robot: Arms) -> None:
    await robot.gate.wait()


@action
@lock(GRIPPER, wait=False)
async def poke(robot: Arms) -> None:
    robot.log.append("poke")


@action
@lock(CAMERA, wait=False)
async def snap(robot: Arms) -> None:
    robot.log.append("snap")


@pytest.mark.asyncio
async def test_unnamed_resources_lock_like_named_ones_and_never_each_other() -> None:
    async with Arms() as robot:
        holder = grip(robot)
        await settle()
        with pytest.raises(ActionSkipped) as skipped:
            await poke(robot)
        await snap(robot)  # another unnamed resource: free
        assert robot.resources.owner(GRIPPER) is holder
        robot.gate.set()
        await holder
    assert robot.log == ["snap"]
    assert str(skipped.value) == (
        f"skipped: resource {GRIPPER.name!r} is busy (held by grip#{holder.id})"
    )
