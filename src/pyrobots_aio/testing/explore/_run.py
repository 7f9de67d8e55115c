"""One run of a behaviour under a schedule, in lockstep virtual time, and its invariants."""

from __future__ import annotations

import asyncio
import logging
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from ... import ActionFinished, ActionStarted, ExecEvent, Robot
from ...loops import run_lockstep
from ...recording import JsonlRecorder
from .._events import EventLog
from ._invariants import Invariant
from ._schedule import At, Hit, On, Target

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Sequence
    from pathlib import Path

R = TypeVar("R", bound=Robot)

_log = logging.getLogger("pyrobots_aio.testing.explore")

_BOUNDARIES: dict[str, type[ExecEvent]] = {"start": ActionStarted, "end": ActionFinished}


@dataclass
class Run(Generic[R]):
    """What happened in one run: the test's view after it, for the invariants.

    Attributes:
        schedule: The hits asked for.
        robot: The robot (stopped by now).
        events: Every executive event of the run.
        hits: The hits that came, with the robot's time of each.
        result: What the behaviour returned (None if it raised or was cut short).
        error: What it raised, or None.
        docked: Whether the robot was docked when the behaviour ended.
        time: Simulated seconds from the behaviour's start to its end.
        violations: What broke, in words (empty: every invariant held).
    """

    schedule: tuple[Hit, ...]
    robot: R
    events: EventLog
    hits: list[tuple[float, Hit]] = field(default_factory=list)
    result: object = None
    error: BaseException | None = None
    docked: bool = False
    time: float = 0.0
    violations: list[str] = field(default_factory=list)


class _Watch:
    """Collects the violations seen during a run; the first one ends the behaviour."""

    def __init__(self, run: Run[Any]) -> None:
        self._run = run
        self.task: asyncio.Task[object] | None = None
        self.fault: BaseException | None = None

    def fail(self, why: str) -> None:
        _log.info("invariant broken: %s", why)
        self._run.violations.append(why)
        self._stop()

    def broke(self, fault: BaseException) -> None:
        """A disturbance could not be applied: the run stops, and the fault is raised after it."""
        self.fault = self.fault or fault
        self._stop()

    def _stop(self) -> None:
        if self.task is not None:
            self.task.cancel("explore: an invariant broke")


class _Arming:
    """The schedule set on a running robot: timers for `At`, boundary counts for `On`."""

    def __init__(self, target: Target, run: Run[Any], watch: _Watch, start: float) -> None:
        self._target, self._run, self._watch = target, run, watch
        self._loop = asyncio.get_running_loop()
        self._seen: dict[tuple[type[ExecEvent], str], int] = {}
        self._waiting: dict[tuple[type[ExecEvent], str, int], list[Hit]] = {}
        self._timers: list[asyncio.Handle] = []
        for hit in run.schedule:
            if isinstance(hit.when, At):
                self._timers.append(self._loop.call_at(start + hit.when.time, self._fire, hit))
            else:
                self._waiting.setdefault(_boundary(hit.when), []).append(hit)
        if self._waiting:
            target.robot.instruments.add(self)

    def on_event(self, event: ExecEvent) -> None:
        key = (type(event), event.name or "")
        if key[0] not in (ActionStarted, ActionFinished):
            return
        count = self._seen[key] = self._seen.get(key, 0) + 1
        for hit in self._waiting.pop((*key, count), ()):
            # on the next iteration, as a sensor update would come (see inject_state)
            self._timers.append(self._loop.call_soon(self._fire, hit))

    def _fire(self, hit: Hit) -> None:
        robot = self._target.robot
        if not robot.is_running:
            return
        self._run.hits.append((robot.time(), hit))
        robot.state.update(disturbance=repr(hit.what))
        try:
            hit.what.apply(self._target)
        except Exception as fault:
            self._watch.broke(fault)

    def disarm(self) -> None:
        self._target.robot.instruments.remove(self)
        for timer in self._timers:
            timer.cancel()
        self._target.undo()


def _boundary(when: On) -> tuple[type[ExecEvent], str, int]:
    return _BOUNDARIES[when.at], when.action, when.nth


def _ending(task: asyncio.Task[object], run: Run[Any]) -> None:
    """Note the behaviour's result or error in ``run``."""
    if task.cancelled():
        return
    run.error = task.exception()
    if run.error is None:
        run.result = task.result()


class Runner(Generic[R]):
    """Runs a behaviour on a fresh base under a schedule and checks its invariants."""

    def __init__(
        self,
        behaviour: Callable[[R], Awaitable[object]],
        base: Callable[[], R],
        invariants: Sequence[Invariant | Callable[[Run[R]], None]],
        time_limit: float,
    ) -> None:
        self.behaviour, self.base = behaviour, base
        self.invariants, self.time_limit = tuple(invariants), time_limit

    def run(self, schedule: Sequence[Hit], record: Path | None) -> Run[R]:
        """One run in lockstep virtual time (a loop of its own), recorded to ``record``."""
        return run_lockstep(self._main, tuple(schedule), record)

    async def _main(self, schedule: tuple[Hit, ...], record: Path | None) -> Run[R]:
        robot = self.base()
        run = Run(schedule, robot, EventLog())
        robot.instruments.add(run.events)
        watch = _Watch(run)
        with JsonlRecorder(record).attach(robot) if record is not None else nullcontext():
            async with robot:
                await self._drive(run, watch)
        if watch.fault is not None:
            raise watch.fault
        if not run.violations:
            self._after(run)
        return run

    async def _drive(self, run: Run[R], watch: _Watch) -> None:
        robot = run.robot
        for invariant in self.invariants:
            if isinstance(invariant, Invariant):
                invariant.watch(robot, watch.fail)
        start = robot.time()
        task: asyncio.Task[object] = asyncio.create_task(self._behave(robot))
        watch.task = task
        arming = _Arming(Target(robot, asyncio.get_running_loop()), run, watch, start)
        try:
            await asyncio.wait([task], timeout=self.time_limit)
            if not task.done():
                watch.fail(f"the behaviour did not end within {self.time_limit} s")
                await asyncio.wait([task])
        finally:
            arming.disarm()
            task.cancel()  # done by now, unless this run itself is being cancelled
        run.time, run.docked = robot.time() - start, bool(robot.state.get("docked"))
        _ending(task, run)

    async def _behave(self, robot: R) -> object:
        return await self.behaviour(robot)

    def _after(self, run: Run[R]) -> None:
        for invariant in self.invariants:
            check = invariant.after if isinstance(invariant, Invariant) else invariant
            try:
                check(run)
            except AssertionError as broken:
                run.violations.append(str(broken) or f"{invariant!r} does not hold")
