"""StateMachine: a master controller's phases, as actions joined by events and outcomes.

A state is an action; the machine (itself an action) runs the current
state's action as its child and waits for whichever comes first: a `When`
event of that state (a one-shot monitor, as ``robot.on`` makes) or the
action's end, whose `Outcome` picks the next state. An event cancels the
state's action (with a reason naming the transition) and waits for its
cleanup before the next state starts. An emergency stop cancels the state's
action too (the machine hands it over, a `StopWatch`), and the machine takes
its failure path. Everything that can be wrong with the machine's shape is
refused when it is built (`StateMachineError`); the state keys its events
watch are checked when it starts.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections.abc import Callable, Iterable, Mapping
from typing import TYPE_CHECKING, Any, NamedTuple, Unpack, cast

from .._exceptions import EmergencyStopError, StateMachineError
from ..actions import Action, ActionHandle, BoundAction, Outcome, action
from ..events._conditions import check_poll, parse
from ._stop import StopWatch

if TYPE_CHECKING:
    from ..events import Conditions
    from ..robot import Robot

_log = logging.getLogger("pyrobots_aio.supervision")
ANY = "*"
"""The source of a transition that leaves every state (but its own target and final states)."""

StateAction = Callable[..., Any]
"""A state's action: an `Action` (called with the robot), a bound action, a function of
the robot that starts an action and returns its handle, or an ``async def`` (made an action)."""


class When:
    """An event that triggers a transition: a condition on a state key, or a predicate.

    The same ``var`` and condition keywords as ``robot.on`` (``becomes=``,
    ``value=``, ``above=`` ..., ``held_for=``; ``poll=`` for a predicate),
    checked at once: a malformed condition is refused here, when the machine
    is built.

    Raises:
        InvalidConditionError: No condition, two, or a wrong one.

    Examples:
        >>> When("bumper", becomes=True)
        When('bumper', becomes=True)
    """

    __slots__ = ("_described", "condition", "poll", "var")

    def __init__(
        self,
        var: str | Callable[[Any], object],
        poll: float | None = None,
        **condition: Unpack[Conditions],
    ) -> None:
        key = _key_or_predicate(var)
        parsed = parse(key, condition)
        self.var = var
        self.poll = check_poll(poll, key)
        self.condition: dict[str, Any] = dict(condition)
        name = key if key is not None else getattr(var, "__qualname__", repr(var))
        self._described = f"{name} {parsed.describe()}".strip()

    def describe(self) -> str:
        """The event in words, e.g. ``bumper becomes=True``."""
        return self._described

    def __repr__(self) -> str:
        parts = [repr(self.var), *(f"{k}={v!r}" for k, v in self.condition.items())]
        if self.poll is not None:
            parts.append(f"poll={self.poll!r}")
        return f"When({', '.join(parts)})"


def _key_or_predicate(var: object) -> str | None:
    """``var`` if it is a state key, None if it is a predicate; else `StateMachineError`."""
    if isinstance(var, str):
        return var
    if not callable(var):
        msg = f"When() watches a state key or a predicate f(robot), got {var!r}"
        raise StateMachineError(msg)
    return None


class Transition(NamedTuple):
    """``(source, target, trigger)``: leave ``source`` for ``target`` on an `Outcome` or `When`."""

    source: str
    target: str
    trigger: Outcome | When


class StateMachine(Action[Any, [], str]):
    """A state machine whose states are actions and whose transitions are events or outcomes.

    It is an action (start it as ``machine(robot)``; attach it, retry it, make
    it the state of another machine): it runs from ``initial``, each state's
    action as its child, and returns the name of the state it ends in. A
    state leaves:

    - on a `When` event of that state (or of ``"*"``, any other state): the
      state's action is cancelled (reason ``"<name>: a -> b on <event>"``),
      its cleanup awaited, then the target starts;
    - when its action ends, on the transition for that `Outcome` (its own,
      else ``"*"``'s). With none, the machine ends: returning the state's
      name if the action succeeded, else raising what awaiting it raises;
    - on an emergency stop (``robot.emergency_stop``): the stop cancels the
      state's action (reason ``"emergency stop: <reason>"``), and once its
      cleanup is over the machine takes the state's FAILED transition (its
      own, else ``"*"``'s), whatever the action's outcome: a CANCELLED
      transition is for other cancellations. With none, the machine fails
      with `EmergencyStopError`. The machine itself is not cancelled, and
      the states it enters while the stop is latched run (the recovery).

    A state whose action is None is final: entering it ends the machine.
    The current state is written to the state key ``<name>_state`` and the
    transitions so far (the last ``history``, as ``"a -> b: cause"``) to
    ``<name>_history``, so recordings keep them.

    Args:
        name: The machine's name (its action's, and its state keys' prefix).
        states: State names to their actions (None: a final state), in order.
        transitions: `Transition` or ``(source, target, trigger)`` tuples.
        initial: The first state (default: the first of ``states``).
        history: How many transitions ``<name>_history`` keeps.

    Raises:
        StateMachineError: An undeclared state, a bad trigger, a transition
            out of a final state, two transitions on the same outcome, a
            state that is not an action.

    Examples:
        >>> from pyrobots_aio import Outcome, Robot, action
        >>> from pyrobots_aio.sim import run
        >>> @action
        ... async def work(robot: Robot) -> None:
        ...     await robot.sleep(1)
        ...     raise RuntimeError("jammed")
        >>> @action
        ... async def clear_jam(robot: Robot) -> None:
        ...     await robot.sleep(1)
        >>> machine = StateMachine(
        ...     "cell",
        ...     {"work": work, "repair": clear_jam, "stopped": None},
        ...     [("work", "repair", Outcome.FAILED), ("repair", "stopped", Outcome.SUCCEEDED)],
        ... )
        >>> async def main() -> tuple[str, ...]:
        ...     async with Robot() as robot:
        ...         return (await machine(robot), *robot.state.cell_history)
        >>> for line in run(main):
        ...     print(line)
        stopped
        work -> repair: failed: RuntimeError('jammed')
        repair -> stopped: succeeded
    """

    def __init__(
        self,
        name: str,
        states: Mapping[str, StateAction | None],
        transitions: Iterable[Transition | tuple[str, str, Outcome | When]],
        *,
        initial: str | None = None,
        history: int = 100,
    ) -> None:
        if not isinstance(name, str) or not name:
            msg = f"a StateMachine needs a name, a non-empty string; got {name!r}"
            raise StateMachineError(msg)
        self.states = _check_states(name, states)
        self.initial = _check_initial(name, self.states, initial)
        if isinstance(history, bool) or not isinstance(history, int) or history < 1:
            msg = f"StateMachine {name!r}: history must be a positive int, got {history!r}"
            raise StateMachineError(msg)
        self.history = history
        self.transitions = tuple(_check_transition(name, self.states, t) for t in transitions)
        self._outcomes = _outcome_table(name, self.transitions)

        async def run(robot: Any) -> str:
            return await self._run(robot)

        run.__name__ = run.__qualname__ = name
        super().__init__(run)

    @property
    def state_key(self) -> str:
        """The state key holding the current state's name."""
        return f"{self.name}_state"

    @property
    def history_key(self) -> str:
        """The state key holding the transitions so far."""
        return f"{self.name}_history"

    # -- running --------------------------------------------------------------------

    async def _run(self, robot: Robot) -> str:
        keys = {t.trigger.var for t in self.transitions if isinstance(t.trigger, When)}
        robot.state.require(*(key for key in keys if isinstance(key, str)))
        state, history = self.initial, tuple[str, ...]()
        robot.state.update({self.state_key: state, self.history_key: history})
        while (spec := self.states[state]) is not None:
            target, cause = await self._step(robot, state, spec)
            if target is None:
                break
            history = (*history, f"{state} -> {target}: {cause}")[-self.history :]
            robot.state.update({self.state_key: target, self.history_key: history})
            _log.info("%s: %s", self.name, history[-1])
            state = target
        return state

    async def _step(self, robot: Robot, state: str, spec: StateAction) -> tuple[str | None, str]:
        """Run one state; return the next state (None: the machine ends) and why."""
        handle = _start(spec, robot, state)
        with StopWatch(robot, handle) as stop:  # a stop cancels the state's action
            event = await self._first_of(robot, state, handle)
            if event is not None:
                handle.cancel(f"{self.name}: {state} -> {event[0]} on {event[1]}")
                await handle.wait_done()
        if stop.reason is not None:
            return self._failure_path(state, handle, stop.reason)
        return event if event is not None else self._after(state, handle)

    async def _first_of(
        self, robot: Robot, state: str, handle: ActionHandle[Any]
    ) -> tuple[str, str] | None:
        """Wait for the state's action to end (None) or an event: ``(target, the event)``."""
        decided: asyncio.Future[tuple[str, str] | None] = asyncio.get_running_loop().create_future()

        def decide(choice: tuple[str, str] | None) -> None:
            if not decided.done():
                decided.set_result(choice)

        handle.add_done_callback(lambda _: decide(None))
        monitors = [
            robot.on(when.var, poll=when.poll, **when.condition).do(
                decide, (target, when.describe())
            )
            for when, target in self._events(state)
        ]
        try:
            return await decided
        finally:
            for monitor in monitors:
                monitor.stop_monitoring()

    def _after(self, state: str, handle: ActionHandle[Any]) -> tuple[str | None, str]:
        """The next state (None: the machine ends) once the state's action is done, and why."""
        outcome = handle.outcome
        error = handle.exception()  # retrieved: a transition handles it, or we raise it
        target = self._target(state, outcome)
        if target is None:
            if error is not None:  # no transition for a failure: it is the machine's
                raise error
            return None, ""
        return target, _cause(handle, error)

    def _failure_path(self, state: str, handle: ActionHandle[Any], reason: str) -> tuple[str, str]:
        """After an emergency stop: the state's FAILED transition, or `EmergencyStopError`."""
        error = handle.exception()  # retrieved: the stop ended it, whatever its outcome
        target = self._target(state, Outcome.FAILED)
        if target is None:
            what = f"StateMachine {self.name!r} in state {state!r}"
            raise EmergencyStopError(what, reason) from error
        return target, f"emergency stop: {reason}"

    def _target(self, state: str, outcome: Outcome) -> str | None:
        """The state that ``state`` leaves for on ``outcome``: its own transition, else ``*``'s."""
        return self._outcomes.get((state, outcome), self._outcomes.get((ANY, outcome)))

    def _events(self, state: str) -> list[tuple[When, str]]:
        """The event transitions that leave ``state``: each `When` and its target."""
        return [
            (t.trigger, t.target)
            for t in self.transitions
            if isinstance(t.trigger, When)
            and (t.source == state or (t.source == ANY and t.target != state))
        ]

    def __repr__(self) -> str:
        return f"<StateMachine {self.name} states={list(self.states)}>"


def _cause(handle: ActionHandle[Any], error: BaseException | None) -> str:
    """How a state's action ended, for the history: ``failed: RuntimeError('jammed')``."""
    outcome = handle.outcome
    if outcome is Outcome.CANCELLED:
        reason = handle.cancel_reason
        return f"cancelled: {reason}" if reason else "cancelled"
    if outcome is Outcome.FAILED:
        return f"failed: {error!r}"
    return f"{outcome.value}: {error}" if error is not None else outcome.value


def _start(spec: StateAction, robot: Robot, state: str) -> ActionHandle[Any]:
    handle = spec() if isinstance(spec, BoundAction) else spec(robot)
    if not isinstance(handle, ActionHandle):
        msg = f"state {state!r}: {spec!r} returned {handle!r}, not the handle of an action"
        raise StateMachineError(msg)
    return handle


# -- building ---------------------------------------------------------------------------


def _check_states(name: str, states: object) -> dict[str, StateAction | None]:
    if not isinstance(states, Mapping) or not states:
        msg = (
            f"StateMachine {name!r} needs states: a mapping of state names to actions "
            f"(None for a final state), got {states!r}"
        )
        raise StateMachineError(msg)
    checked: dict[str, StateAction | None] = {}
    for state, spec in states.items():
        if not isinstance(state, str) or not state or state == ANY:
            msg = f"StateMachine {name!r}: a state name must be a non-empty string, not {state!r}"
            raise StateMachineError(msg)
        if spec is not None and not callable(spec):
            msg = (
                f"state {state!r} of {name!r} is {spec!r}: give an @action, a bound action, "
                "a function of the robot returning an action's handle, or None (final)"
            )
            raise StateMachineError(msg)
        plain = inspect.iscoroutinefunction(spec) and not isinstance(spec, Action)
        checked[state] = action(cast("Any", spec)) if plain else cast("StateAction | None", spec)
    return checked


def _check_initial(name: str, states: dict[str, StateAction | None], initial: str | None) -> str:
    if initial is None:
        return next(iter(states))
    if initial not in states:
        msg = f"initial state {initial!r} of {name!r} is not declared; states: {list(states)}"
        raise StateMachineError(msg)
    return initial


def _check_transition(name: str, states: dict[str, StateAction | None], item: object) -> Transition:
    if not isinstance(item, tuple) or len(item) != 3:
        msg = f"transition {item!r} of {name!r}: give (source, target, trigger)"
        raise StateMachineError(msg)
    source, target, trigger = item
    where = f"transition {source!r} -> {target!r} of {name!r}"
    for state in (source, target):
        if state not in states and not (state is source and state == ANY):
            anywhere = " (or '*' as the source: any state)" if state is source else ""
            msg = f"{where}: unknown state {state!r}; declared states: {list(states)}{anywhere}"
            raise StateMachineError(msg)
    if source != ANY and states[source] is None:
        msg = f"{where}: {source!r} is a final state (no action); no transition leaves it"
        raise StateMachineError(msg)
    if not isinstance(trigger, When) and (
        not isinstance(trigger, Outcome) or trigger is Outcome.NOT_DONE
    ):
        msg = (
            f"{where}: the trigger must be an Outcome (SUCCEEDED, FAILED, CANCELLED, SKIPPED) "
            f"or When(key, **condition), got {trigger!r}"
        )
        raise StateMachineError(msg)
    return Transition(source, target, trigger)


def _outcome_table(
    name: str, transitions: tuple[Transition, ...]
) -> dict[tuple[str, Outcome], str]:
    table: dict[tuple[str, Outcome], str] = {}
    for source, target, trigger in transitions:
        if not isinstance(trigger, Outcome):
            continue
        if (source, trigger) in table:
            msg = (
                f"two transitions of {name!r} leave {source!r} on {trigger.name}: to "
                f"{table[source, trigger]!r} and to {target!r}; keep one"
            )
            raise StateMachineError(msg)
        table[source, trigger] = target
    return table
