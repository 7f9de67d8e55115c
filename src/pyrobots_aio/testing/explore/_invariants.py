"""Invariants: what must hold during and after a run, whatever the disturbances.

An invariant watches the running robot (`Invariant.watch`, calling ``fail``
the moment it breaks, which ends the run) and looks at the finished `Run`
(`Invariant.after`, raising ``AssertionError``). A plain function of the
`Run` that asserts is an invariant too (an after-check).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ... import (
    ActionAbandonment,
    ActionFinished,
    ActionSpawned,
    ExecEvent,
    ResourceAcquired,
    ResourceReleased,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from ... import Robot
    from ._run import Run


class Invariant:
    """A property of every run; override `watch`, `after`, or both."""

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        """Start watching ``robot`` (running, the behaviour about to start); call ``fail(why)``."""

    def after(self, run: Run[Any]) -> None:
        """Check the finished run.

        Raises:
            AssertionError: It does not hold; the message says what happened.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class completes(Invariant):
    """The behaviour returns (no exception) within the scenario's time limit."""

    def after(self, run: Run[Any]) -> None:
        """The behaviour returned."""
        if run.error is not None:
            raise AssertionError(f"the behaviour raised {run.error!r}")


class ends_docked(Invariant):
    """The robot is on its dock (``robot.state.docked``) when the behaviour ends."""

    def after(self, run: Run[Any]) -> None:
        """The robot is docked."""
        if not run.docked:
            raise AssertionError("the robot did not end on its dock")


def commanded(robot: Robot) -> tuple[float, float]:
    """The wheels' command ``(v, w)``: a simulated world's (FakeBase, SimRobot), else the state's.

    A simulated base's state has the odometry's speeds, which lag the command
    (and read zero against a wall); its world has what the wheels are told.
    """
    command = getattr(getattr(robot, "world", None), "command", None)
    if isinstance(command, tuple):
        return command
    return robot.state.get("v") or 0.0, robot.state.get("w") or 0.0


class _WhileHeld(Invariant):
    """An invariant on what may happen once a condition has held for ``grace`` seconds."""

    KEYS: tuple[str, ...] = ()
    """The state keys whose writes it looks at."""

    def __init__(self, grace: float) -> None:
        self.grace = grace

    def __repr__(self) -> str:
        return f"{type(self).__name__}(grace={self.grace!r})"

    def holds(self, robot: Robot) -> bool:
        """Whether the condition holds now."""
        raise NotImplementedError

    def breach(self, robot: Robot, now: float, since: float) -> str | None:
        """What broke, the condition holding since ``since`` (past the grace), or None."""
        raise NotImplementedError

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        """Look at every write of `KEYS`: how long the condition has held, and what happens."""
        since: list[float | None] = [None]

        def check(_: Mapping[str, Any]) -> None:
            if not self.holds(robot):  # at nearly every tick: nothing more to look at
                since[0] = None
                return
            now = robot.time()
            start = since[0] = now if since[0] is None else since[0]
            # ticks land on sums of floats: a press of exactly the grace is not longer than it
            held = now - start > self.grace + 1e-9
            why = self.breach(robot, now, start) if held else None
            if why is not None:
                fail(why)

        robot.state.subscribe(check, self.KEYS)


class no_forward_into_bumper(_WhileHeld):
    """The base never drives forward while a front bumper has been pressed longer than ``grace``.

    Args:
        grace: Seconds a press may last before a forward command counts
            (a reflex needs a tick or two to take the wheels).
    """

    KEYS = ("bumper_left", "bumper_right", "v")

    def __init__(self, grace: float = 0.2) -> None:
        super().__init__(grace)

    def holds(self, robot: Robot) -> bool:
        """A front bumper is pressed."""
        state = robot.state
        return bool(state.get("bumper_left") or state.get("bumper_right"))

    def breach(self, robot: Robot, now: float, since: float) -> str | None:
        """The base drives forward."""
        v, _ = commanded(robot)
        if v <= 0:
            return None
        return (
            f"at t={now:.3f} the base was commanded forward (v={v:.3f} m/s) with the front "
            f"bumper pressed since t={since:.3f} (more than {self.grace} s)"
        )


class still_while_stopped(_WhileHeld):
    """Once the emergency stop has been latched ``grace`` seconds, the wheels stay still."""

    KEYS = ("v", "w")

    def __init__(self, grace: float = 0.05) -> None:
        super().__init__(grace)

    def holds(self, robot: Robot) -> bool:
        """The emergency stop is latched."""
        return robot.emergency_stopped

    def breach(self, robot: Robot, now: float, since: float) -> str | None:
        """The wheels turn."""
        v, w = commanded(robot)
        if not (v or w):
            return None
        return (
            f"at t={now:.3f} the wheels were commanded (v={v:.3f}, w={w:.3f}) under the "
            f"emergency stop latched since t={since:.3f}"
        )


class no_action_outlives_robot(Invariant):
    """Every action has finished when the robot has stopped, none of them abandoned."""

    def after(self, run: Run[Any]) -> None:
        """Every spawned action finished, and none ignored its cancellation."""
        events = run.events
        finished = {e.action for e in events.of_kind(ActionFinished)}
        alive = [
            f"{e.name} #{e.action}"
            for e in events.of_kind(ActionSpawned)
            if e.action not in finished
        ]
        if alive:
            raise AssertionError(f"actions outlived the robot: {alive}")
        abandoned = [f"{e.name} #{e.action}" for e in events.of_kind(ActionAbandonment)]
        if abandoned:
            msg = f"actions ignored their cancellation and were abandoned: {abandoned}"
            raise AssertionError(msg)


class no_resource_held_twice(Invariant):
    """No resource is ever held by two actions at once (a lent one counts as its borrower's)."""

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        """Follow every grant, release and loan of the resources."""
        robot.instruments.add(_Holders(robot, fail))


class _Holders:
    """Who holds each resource, from the executive's resource events.

    An action may take what an ancestor holds (`lock`): each resource has a
    stack of holders, each the descendant of the one below.
    """

    def __init__(self, robot: Robot, fail: Callable[[str], None]) -> None:
        self._robot, self._fail = robot, fail
        self._holders: dict[str, list[int]] = {}
        self._parent: dict[int, int | None] = {}

    def on_event(self, event: ExecEvent) -> None:
        if isinstance(event, ActionSpawned) and event.action is not None:
            self._parent[event.action] = event.parent
        elif isinstance(event, ResourceReleased):
            for leaf in event.leaves:
                stack = self._holders.get(leaf, [])
                if event.action in stack:
                    stack.remove(event.action)
        elif isinstance(event, ResourceAcquired) and event.action is not None:
            for leaf in event.leaves:
                self._acquired(event, leaf, event.action)

    def _acquired(self, event: ResourceAcquired, leaf: str, taker: int) -> None:
        stack = self._holders.setdefault(leaf, [])
        if stack and not self._descends(taker, stack[-1]):
            self._fail(
                f"at t={event.time:.3f} {event.name} #{taker} acquired {leaf!r} "
                f"held by action #{stack[-1]}"
            )
        stack.append(taker)

    def _descends(self, action: int | None, ancestor: int) -> bool:
        while action is not None:
            if action == ancestor:
                return True
            action = self._parent.get(action)
        return False


SAFETY: tuple[Invariant, ...] = (
    no_forward_into_bumper(),
    still_while_stopped(),
    no_action_outlives_robot(),
    no_resource_held_twice(),
)
"""The invariants every scenario checks unless it says otherwise (with `completes` first)."""
