"""A randomized test of the executive: thousands of spawn, cancel, pause and nest operations.

Hypothesis draws programs. The driver (the test task) starts root actions, lets
virtual time pass, cancels, pauses, resumes or awaits random handles, pauses
and resumes everything and cancels everything; each action's body sleeps,
starts children (awaited or not), fails, cancels, pauses or resumes a random
action or calls ``cancel_all_others``, and when cancelled re-raises, swallows the
cancellation, or cleans up first (sleeping, or running a child action). A
frozen body must never go on; a paused action left paused is still cancelled
at shutdown, within the same bound. The
invariants of DESIGN.md §3 are checked as the program runs and once the robot
has shut down; every breach is collected as a message, so a failure shows the
shrunk program and what went wrong.
"""

from __future__ import annotations

import asyncio
import functools
from dataclasses import dataclass
from typing import Any

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from pyrobots_aio import (
    ActionHandle,
    ActionInterrupted,
    ActionState,
    EventKind,
    ExecEvent,
    Outcome,
    Robot,
    action,
)
from pyrobots_aio.actions import current_action

pytestmark = pytest.mark.virtual_time


class Boom(Exception):
    """What a failing body raises."""

    def __init__(self, ident: int) -> None:
        super().__init__(f"action {ident} failed")
        self.ident = ident


@dataclass(frozen=True)
class Sleep:
    seconds: float


@dataclass(frozen=True)
class Spawn:
    body: Body
    awaited: bool


@dataclass(frozen=True)
class Fail:
    pass


@dataclass(frozen=True)
class CancelOne:
    index: int


@dataclass(frozen=True)
class CancelOthers:
    pass


@dataclass(frozen=True)
class PauseOne:
    index: int


@dataclass(frozen=True)
class ResumeOne:
    index: int


@dataclass(frozen=True)
class Reraise:
    pass


@dataclass(frozen=True)
class Swallow:
    pass


@dataclass(frozen=True)
class CleanupSleep:
    seconds: float


@dataclass(frozen=True)
class CleanupSpawn:
    body: Body


@dataclass(frozen=True)
class Body:
    steps: tuple[Sleep | Spawn | Fail | CancelOne | CancelOthers | PauseOne | ResumeOne, ...]
    on_cancel: Reraise | Swallow | CleanupSleep | CleanupSpawn


@dataclass(frozen=True)
class Start:
    body: Body


@dataclass(frozen=True)
class Await:
    index: int
    timeout: float


@dataclass(frozen=True)
class CancelAll:
    pass


@dataclass(frozen=True)
class PauseAll:
    pass


@dataclass(frozen=True)
class ResumeAll:
    pass


SECONDS = st.sampled_from([0.0, 0.1, 0.5, 1.0, 2.5, 5.0])
INDEX = st.integers(min_value=0, max_value=1000)


def weighted(*choices: tuple[int, st.SearchStrategy[Any]]) -> st.SearchStrategy[Any]:
    """One of the strategies, each drawn ``weight`` times as often (one_of drops repeats)."""
    return st.sampled_from([s for weight, s in choices for _ in range(weight)]).flatmap(lambda s: s)


@functools.cache
def bodies(depth: int) -> st.SearchStrategy[Body]:
    """Bodies whose children nest at most ``depth`` levels deeper."""
    child = bodies(depth - 1) if depth else None
    nest = [(3, st.builds(Spawn, child, st.booleans()))] if child is not None else []
    nest_in_cleanup = [(2, st.builds(CleanupSpawn, child))] if child is not None else []
    steps = weighted(  # mostly sleeping and nesting
        (4, st.builds(Sleep, SECONDS)),
        *nest,
        (1, st.builds(Fail)),
        (1, st.builds(CancelOne, INDEX)),
        (1, st.builds(CancelOthers)),
        (1, st.builds(PauseOne, INDEX)),
        (1, st.builds(ResumeOne, INDEX)),
    )
    cleanups = weighted(
        (1, st.builds(Reraise)),
        (1, st.builds(Swallow)),
        (2, st.builds(CleanupSleep, st.sampled_from([0.0, 0.5, 3.0]))),  # 3 s > the grace
        *nest_in_cleanup,
    )
    return st.builds(Body, st.lists(steps, min_size=1, max_size=4).map(tuple), cleanups)


DEPTH, GRACE = 3, 2.0
# A cleanup child is cut at most a grace after its parent's first cancel (with the parent's body,
# cancelled again, or on its own once that body is over) and the deepest cleanup is cut at its
# grace: an action is done DEPTH + 1 graces at most after its cancellation, even one that swallows
# it or starts an action in its cleanup.
SHUTDOWN_BOUND = (DEPTH + 1) * GRACE
programs = st.lists(
    weighted(
        (3, st.builds(Start, bodies(DEPTH))),
        (2, st.builds(Sleep, SECONDS)),
        (2, st.builds(CancelOne, INDEX)),
        (2, st.builds(Await, INDEX, st.sampled_from([0.1, 1.0, 10.0]))),
        (1, st.builds(CancelAll)),
        (2, st.builds(PauseOne, INDEX)),
        (2, st.builds(ResumeOne, INDEX)),
        (1, st.builds(PauseAll)),
        (1, st.builds(ResumeAll)),
    ),
    min_size=10,
    max_size=60,
)


class World:
    """Runs one program on one robot and collects every invariant it breaks."""

    def __init__(self) -> None:
        self.robot = Robot(cancel_grace=GRACE, instruments=[self])
        self.handles: list[ActionHandle[int]] = []
        self.by_id: dict[int, ActionHandle[int]] = {}
        self.ended: dict[int, str] = {}  # how each body ended: returned, failed, swallowed
        self.cancels: dict[int, tuple[object, object, ActionState]] = {}  # reason, by, state
        self.expected: dict[int, tuple[str, int | None]] = {}  # reason and canceller's id
        self.breaches: list[str] = []

    def on_event(self, event: ExecEvent) -> None:
        """The instrument: note each cancellation request and the state it found."""
        if event.kind is EventKind.ACTION_ABANDONED:  # every body here answers cancellation
            self.breaches.append(f"#{event.action} abandoned at {event.data['location']}")
        elif event.kind is EventKind.CANCEL_REQUESTED:
            if event.action in self.cancels:
                self.breaches.append(f"#{event.action}: cancellation requested twice")
            state = self.by_id[event.action].state
            self.cancels[event.action] = (event.data["reason"], event.data["by"], state)

    def spawn(self, body: Body) -> ActionHandle[int]:
        handle = perform(self.robot, body, self)
        self.handles.append(handle)
        self.by_id[handle.id] = handle
        handle.add_done_callback(self.finished)
        return handle

    def finished(self, handle: ActionHandle[int]) -> None:
        late = [h for h in self.handles if h.childof(handle) and not h.done()]
        if late:
            self.breaches.append(f"{handle!r} done before its descendants {late!r}")
        if handle in self.robot.handles():
            self.breaches.append(f"{handle!r} done but still listed as running")

    def check_registry(self, where: str) -> None:
        """``robot.running()`` lists exactly the actions not done yet."""
        running = {info.id for info in self.robot.running()}
        if running != {h.id for h in self.handles if not h.done()}:
            self.breaches.append(f"{where}, running() lists {sorted(running)}")

    def pick(self, index: int) -> ActionHandle[int] | None:
        return self.handles[index % len(self.handles)] if self.handles else None

    def expect_cancelled(self, targets: list[ActionHandle[int]], reason: str) -> None:
        """Each live action of the targets' subtrees gets this reason, but cleanup is spared.

        A second cancel never kills cleanup (DESIGN §11): the cancellation stops at
        actions already cancelled, so what they started since runs on.
        """
        by = current_action.get()
        for h in self.handles:
            if not h.done() and any(reached(h, t) for t in targets):
                self.expected.setdefault(h.id, (reason, None if by is None else by.id))

    def cancel(self, target: ActionHandle[int], reason: str) -> None:
        was_done = target.done()
        self.expect_cancelled([target], reason)
        if target.cancel(reason) is was_done:
            self.breaches.append(
                f"{target!r}.cancel() returned {not was_done} when done={was_done}"
            )

    def check_cancelled_here(self, what: str) -> None:
        """A CancelledError arrived in this task: it must have been cancelled itself."""
        task = asyncio.current_task()
        if task is None or task.cancelling() == 0:
            self.breaches.append(f"CancelledError in {what}, whose task was not cancelled")

    async def await_handle(self, handle: ActionHandle[int], who: str) -> None:
        """Await ``handle``; what it returns or raises must match its outcome."""
        try:
            value = await handle
        except ActionInterrupted as exc:
            ok = handle.cancelled() and exc.handle is handle and exc.reason == handle.cancel_reason
        except Boom as exc:
            ok = handle.outcome is Outcome.FAILED and exc.ident == handle.id
        except asyncio.CancelledError:
            self.check_cancelled_here(f"{who} awaiting {handle!r}")
            raise
        else:
            ok = handle.outcome is Outcome.SUCCEEDED and value == handle.id
        if not ok:
            self.breaches.append(f"awaiting {handle!r} did not match its outcome {handle.outcome}")

    async def cancel_others(self, me: ActionHandle[int]) -> None:
        spared = {me, *(h for h in self.handles if me.childof(h))}
        live = [h for h in self.handles if not h.done() and h not in spared]
        reason = f"others cancelled by #{me.id}"
        self.expect_cancelled(outermost(live, spared), reason)
        try:
            await self.robot.cancel_all_others(reason)
        except asyncio.CancelledError:
            self.check_cancelled_here(f"{me!r} in cancel_all_others")
            raise
        if left := [h for h in live if not h.done()]:
            self.breaches.append(f"cancel_all_others from {me!r} returned before {left!r}")

    def check_thawed(self, me: ActionHandle[int], where: str) -> None:
        """A body that goes on after an await must not be frozen."""
        if me.paused:
            self.breaches.append(f"{me!r} went on while frozen, {where}")

    def pause_or_resume(self, op: PauseOne | ResumeOne, who: str) -> None:
        target = self.pick(op.index)
        if target is None:
            return
        if isinstance(op, PauseOne):
            if target.pause(f"paused by {who}") is target.done():
                self.breaches.append(f"{target!r}.pause() disagreed with done()")
        elif (
            target.resume()
            and target.paused
            and not any(a.paused for a in self.handles if target.childof(a))
        ):
            self.breaches.append(f"{target!r} still paused after resume()")

    async def step(self, me: ActionHandle[int], step: object) -> None:
        self.check_registry(f"before {step} in {me!r}")
        if isinstance(step, PauseOne | ResumeOne):
            self.pause_or_resume(step, f"#{me.id}")
        elif isinstance(step, Sleep):
            await self.robot.sleep(step.seconds)
            self.check_thawed(me, f"after sleeping {step.seconds}")
        elif isinstance(step, Spawn):
            child = self.spawn(step.body)
            if step.awaited:
                await self.await_handle(child, repr(me))
                self.check_thawed(me, f"after awaiting {child!r}")
        elif isinstance(step, Fail):
            self.ended[me.id] = "failed"
            raise Boom(me.id)
        elif isinstance(step, CancelOne):
            if (target := self.pick(step.index)) is not None:
                self.cancel(target, f"cancelled by #{me.id}")
        elif isinstance(step, CancelOthers):
            await self.cancel_others(me)

    async def clean_up(self, me: ActionHandle[int], cleanup: object) -> None:
        if isinstance(cleanup, CleanupSleep):
            await self.robot.sleep(cleanup.seconds)
        elif isinstance(cleanup, CleanupSpawn):
            await self.await_handle(self.spawn(cleanup.body), f"the cleanup of {me!r}")


@action
async def perform(robot: Robot, body: Body, world: World) -> int:
    me = current_action.get()
    assert me is not None
    try:
        for step in body.steps:
            await world.step(me, step)
    except asyncio.CancelledError:
        if not me.cancel_requested:
            world.breaches.append(f"{me!r} got CancelledError without a cancellation request")
        world.check_cancelled_here(f"the body of {me!r}")
        if isinstance(body.on_cancel, Swallow):
            world.ended[me.id] = "swallowed"
            return int(me.id)
        await world.clean_up(me, body.on_cancel)
        raise
    world.ended[me.id] = "returned"
    return int(me.id)


def outermost(
    live: list[ActionHandle[int]], spared: set[ActionHandle[int]]
) -> list[ActionHandle[int]]:
    """What cancel_all cancels: the live actions whose parent is None or spared."""
    return [h for h in live if h.parent is None or h.parent in spared]


def reached(handle: ActionHandle[int], target: ActionHandle[int]) -> bool:
    """Whether cancelling ``target`` cancels ``handle``: in its subtree, none cancelled between."""
    node: ActionHandle[Any] | None = handle
    while node is not None:
        if node.cancel_requested:
            return False
        if node is target:
            return True
        node = node.parent
    return False


Op = Start | Sleep | CancelOne | Await | CancelAll | PauseOne | ResumeOne | PauseAll | ResumeAll


async def run(world: World, program: list[Op]) -> None:
    """The driver: run ``program`` from outside any action, checking the registry after each op."""
    robot = world.robot
    async with robot:
        for number, op in enumerate(program):
            await drive_op(world, op, number)
            world.check_registry(f"after op {number}")
        live = [h for h in world.handles if not h.done()]
        world.expect_cancelled(outermost(live, set()), "robot shutting down")
        exit_at = robot.time()
    took = asyncio.get_running_loop().time() - exit_at
    if took > SHUTDOWN_BOUND:
        world.breaches.append(f"shutdown took {took} s")


async def drive_op(world: World, op: Op, number: int) -> None:
    """One op of the driver's program."""
    robot = world.robot
    if isinstance(op, Start):
        world.spawn(op.body)
    elif isinstance(op, Sleep):
        await robot.sleep(op.seconds)
    elif isinstance(op, CancelOne | Await) and (target := world.pick(op.index)):
        if isinstance(op, CancelOne):
            world.cancel(target, f"driver op {number}")
        else:
            await wait_for(world, target, op.timeout)
    elif isinstance(op, PauseOne | ResumeOne):
        world.pause_or_resume(op, "the driver")
    elif isinstance(op, PauseAll):
        robot.pause_all("the driver")
    elif isinstance(op, ResumeAll):
        robot.resume_all()
        if paused := [h for h in world.handles if h.paused]:
            world.breaches.append(f"resume_all left {paused!r} paused")
    elif isinstance(op, CancelAll):
        live = [h for h in world.handles if not h.done()]
        world.expect_cancelled(outermost(live, set()), f"driver op {number}")
        await robot.cancel_all(f"driver op {number}")
        if robot.handles():
            world.breaches.append(f"cancel_all left {robot.handles()!r} running")


async def wait_for(world: World, target: ActionHandle[int], seconds: float) -> None:
    try:
        async with asyncio.timeout(seconds):
            await world.await_handle(target, "the driver")
    except TimeoutError:  # the driver's deadline cancels the action it waited for
        if not (target.done() or target.cancel_requested):
            world.breaches.append(f"{target!r} not cancelled when its awaiter timed out")


def expected_outcome(world: World, handle: ActionHandle[int]) -> Outcome | None:
    """CANCELLED if cancellation was requested before the action was done, else what the body did.

    A failure is never masked: a body that failed before the request (its handle was
    winding up its children) stays FAILED.
    """
    ended = world.ended.get(handle.id)
    cancel = world.cancels.get(handle.id)
    if cancel is not None and not (cancel[2] is ActionState.FINISHING and ended == "failed"):
        return Outcome.CANCELLED
    return {"returned": Outcome.SUCCEEDED, "failed": Outcome.FAILED}.get(ended or "")


def check_outcome(world: World, handle: ActionHandle[int]) -> None:
    cancel = world.cancels.get(handle.id)
    if not handle.done() or handle.outcome is not expected_outcome(world, handle):
        world.breaches.append(f"{handle!r}: {handle.outcome}, body {world.ended.get(handle.id)}")
    if handle.cancel_requested is not (cancel is not None):
        world.breaches.append(f"{handle!r}: cancel_requested disagrees with the events")
    if cancel is not None and handle.cancel_reason != cancel[0]:
        world.breaches.append(f"{handle!r}: reason {handle.cancel_reason!r}, event {cancel[0]!r}")
    expected = world.expected.get(handle.id)
    if expected is not None and (cancel is None or expected != (cancel[0], cancel[1])):
        world.breaches.append(f"{handle!r}: expected cancellation {expected}, got {cancel}")
    error = handle.exception() if handle.done() else None
    if handle.cancelled() and not (isinstance(error, ActionInterrupted) and error.handle is handle):
        world.breaches.append(f"{handle!r}: cancelled, but awaiting it raises {error!r}")
    if handle.outcome is Outcome.FAILED and not (
        isinstance(error, Boom) and error.ident == handle.id
    ):
        world.breaches.append(f"{handle!r}: failed, but awaiting it raises {error!r}")


@pytest.mark.asyncio
@settings(
    max_examples=400,
    derandomize=True,
    database=None,
    phases=[Phase.generate, Phase.shrink],  # no explain phase: it traces, slowly
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(program=programs)
async def test_random_spawn_cancel_pause_nest_keeps_the_invariants(program: list[Op]) -> None:
    """Structure, outcomes, what awaiting raises, the registry and shutdown stay as designed."""
    before = asyncio.all_tasks()
    world = World()
    await run(world, program)
    for handle in world.handles:
        check_outcome(world, handle)
    await asyncio.sleep(0)
    left = [t for t in asyncio.all_tasks() - before if not t.done()]
    assert world.breaches == []
    assert left == []
    assert not world.robot.is_running
    assert world.robot.running() == []
