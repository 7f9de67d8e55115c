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
        assert run.error is None, f"the behaviour raised {run.error!r}"


class ends_docked(Invariant):
    """The robot is on its dock (``robot.state.docked``) when the behaviour ends."""

    def after(self, run: Run[Any]) -> None:
        """The robot is docked."""
        assert run.docked, "the robot did not end on its dock"


class no_forward_into_bumper(Invariant):
    """The base never drives forward while a front bumper has been pressed longer than ``grace``.

    Args:
        grace: Seconds a press may last before a forward command counts
            (a reflex needs a tick or two to take the wheels).
    """

    def __init__(self, grace: float = 0.2) -> None:
        self.grace = grace

    def __repr__(self) -> str:
        return f"no_forward_into_bumper(grace={self.grace!r})"

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        """Watch the bumper and the commanded speed at every write."""
        since: list[float | None] = [None]

        def check(_: Mapping[str, Any]) -> None:
            state, now = robot.state, robot.time()
            if not (state.get("bumper_left") or state.get("bumper_right")):
                since[0] = None
                return
            pressed = since[0] = now if since[0] is None else since[0]
            v = state.get("v") or 0.0
            if v > 0 and now - pressed > self.grace:
                fail(
                    f"at t={now:.3f} the base drove forward (v={v:.3f} m/s) with the front "
                    f"bumper pressed since t={pressed:.3f} (more than {self.grace} s)"
                )

        robot.state.subscribe(check, ("bumper_left", "bumper_right", "v"))


class still_while_stopped(Invariant):
    """Once the emergency stop has been latched ``grace`` seconds, the wheels stay still."""

    def __init__(self, grace: float = 0.05) -> None:
        self.grace = grace

    def __repr__(self) -> str:
        return f"still_while_stopped(grace={self.grace!r})"

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        """Watch the commanded speeds while the stop is latched."""
        since: list[float | None] = [None]

        def check(_: Mapping[str, Any]) -> None:
            now = robot.time()
            if not robot.emergency_stopped:
                since[0] = None
                return
            latched = since[0] = now if since[0] is None else since[0]
            v, w = robot.state.get("v") or 0.0, robot.state.get("w") or 0.0
            if (v or w) and now - latched > self.grace:
                fail(
                    f"at t={now:.3f} the wheels turned (v={v:.3f}, w={w:.3f}) under the "
                    f"emergency stop latched since t={latched:.3f}"
                )

        robot.state.subscribe(check, ("v", "w"))


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
        assert not alive, f"actions outlived the robot: {alive}"
        abandoned = [f"{e.name} #{e.action}" for e in events.of_kind(ActionAbandonment)]
        assert not abandoned, f"actions ignored their cancellation and were abandoned: {abandoned}"


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
