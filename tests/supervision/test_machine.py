"""StateMachine: states are actions, transitions events or outcomes, refused when malformed."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from pyrobots_aio import (
    ActionCancelled,
    EventKind,
    InvalidConditionError,
    Outcome,
    Resource,
    Robot,
    StateMachine,
    StateMachineError,
    UnknownStateKeyError,
    action,
    lock,
)
from pyrobots_aio.recording import JsonlRecorder, load
from pyrobots_aio.supervision import Transition, When
from pyrobots_aio.testing import EventLog

ARM = Resource("arm")
S, F, C = Outcome.SUCCEEDED, Outcome.FAILED, Outcome.CANCELLED


class Cell(Robot):
    """A work cell: its actions note when they start and end."""

    def __init__(self, **options: Any) -> None:
        self.record = EventLog()
        super().__init__(instruments=[self.record], **options)
        self.notes: list[tuple[float, str]] = []
        self.jams = 1

    def note(self, what: str) -> None:
        self.notes.append((round(self.time(), 6), what))

    @action
    @lock(ARM)
    async def work(self) -> str:
        self.note("work")
        try:
            await self.sleep(1)
        except ActionCancelled:
            await self.sleep(0.5)  # put the part down
            self.note("part down")
            raise
        if self.jams:
            self.jams -= 1
            raise RuntimeError("jammed")
        return "done"

    @action
    async def repair(self) -> None:
        self.note("repair")
        await self.sleep(2)

    @action
    async def idle(self) -> None:
        self.note("idle")
        await self.sleep(3600)


CELL = StateMachine(
    "cell",
    {"work": Cell.work, "repair": Cell.repair, "idle": Cell.idle, "off": None},
    [
        ("work", "repair", F),
        ("repair", "work", S),
        ("work", "idle", S),
        Transition("*", "off", When("power", becomes=False)),
        ("idle", "work", When("orders", above=0)),
    ],
)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_outcomes_and_events_move_it_through_its_states() -> None:
    async with Cell() as robot:
        robot.state.update(power=True, orders=0)
        machine = CELL(robot)
        await robot.sleep(5)
        assert robot.state.cell_state == "idle"
        robot.state.orders = 1  # level condition: it holds, the idle state leaves
        await robot.sleep(0.5)
        assert robot.state.cell_state == "work"
        robot.state.power = False
        assert await machine == "off"
        assert robot.time() == 6.0  # once the work's cleanup is over
    assert robot.notes == [
        (0, "work"),
        (1, "repair"),
        (3, "work"),
        (4, "idle"),
        (5, "work"),
        (6, "part down"),
    ]
    assert robot.state.cell_history == (
        "work -> repair: failed: RuntimeError('jammed')",
        "repair -> work: succeeded",
        "work -> idle: succeeded",
        "idle -> work: orders above=0",
        "work -> off: power becomes=False",
    )
    log = robot.record
    assert log.first(EventKind.ACTION_SPAWNED, "cell").action == machine.id
    spawned = log.of_kind(EventKind.ACTION_SPAWNED)
    assert [(e.name, e.data["parent"]) for e in spawned[1:]] == [
        (name, machine.id) for name in ("work", "repair", "work", "idle", "work")
    ]
    (cancel,) = log.cancellations("work")
    assert cancel.data["reason"] == "cell: work -> off on power becomes=False"


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_state_and_history_are_in_the_recording(tmp_path: Path) -> None:
    robot = Cell()
    with JsonlRecorder(tmp_path / "cell.jsonl").attach(robot):
        async with robot:
            robot.state.update(power=True, orders=0)
            machine = CELL(robot)
            await robot.sleep(4.5)
            robot.state.power = False
            assert await machine == "off"
    recording = load(tmp_path / "cell.jsonl")
    state = recording.samples["cell_state"]
    assert list(zip(state.times, state.values, strict=True)) == [
        (0, "work"),
        (1, "repair"),
        (3, "work"),
        (4, "idle"),
        (4.5, "off"),
    ]
    history = recording.samples["cell_history"]
    assert list(history.times) == [0, 1, 3, 4, 4.5]
    assert history.values[-1] == [
        "work -> repair: failed: RuntimeError('jammed')",
        "repair -> work: succeeded",
        "work -> idle: succeeded",
        "idle -> off: power becomes=False",
    ]
    names = {e.name for e in recording.events if e.kind is EventKind.ACTION_SPAWNED}
    assert names == {"cell", "work", "repair", "idle"}


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_outcome_with_no_transition_ends_it() -> None:
    solo = StateMachine("solo", {"work": Cell.work}, [])
    async with Cell() as robot:
        robot.jams = 0
        assert await solo(robot) == "work"  # it succeeded: the machine ends there
        robot.jams = 1
        handle = solo(robot)
        with pytest.raises(RuntimeError, match=r"^jammed$"):  # it failed: the machine fails
            await handle
        assert handle.outcome is Outcome.FAILED
        assert robot.state.solo_history == ()


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_emergency_stop_takes_the_failure_path_to_recover() -> None:
    guarded = StateMachine(
        "guarded",
        {"work": Cell.work, "recover": Cell.repair, "stopped": None},
        [("work", "recover", F), ("recover", "stopped", S)],
    )
    async with Cell() as robot:
        machine = guarded(robot)
        await robot.sleep(0.5)
        await robot.emergency_stop("operator")  # work holds the arm: preempted
        assert await machine == "stopped"
        assert robot.state.guarded_history == (
            "work -> recover: emergency stop: operator",
            "recover -> stopped: succeeded",
        )
        assert robot.time() == 3.0


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_cancelling_it_cancels_its_state_and_stops_its_events() -> None:
    async with Cell() as robot:
        robot.state.update(power=True, orders=0)
        machine = CELL(robot)
        await robot.sleep(4.5)
        machine.cancel("end of shift")
        assert await machine.wait_done() is Outcome.CANCELLED
        (idle,) = robot.record.cancellations("idle")
        assert idle.data["reason"] == "end of shift"
        robot.state.orders = 5
        robot.state.power = False
        await robot.sleep(10)
        assert robot.state.cell_state == "idle"
        assert robot.running() == []


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_states_may_be_bound_actions_functions_coroutines_and_machines() -> None:
    async def warm_up(robot: Robot) -> None:
        await robot.sleep(1)

    inner = StateMachine("inner", {"work": Cell.work, "end": None}, [("work", "end", S)])
    outer = StateMachine(
        "outer",
        {
            "warm": warm_up,
            "run": inner,
            "rest": lambda robot: robot.idle(),
            "end": None,
        },
        [("warm", "run", S), ("run", "rest", S), ("rest", "end", When("done", becomes=True))],
        history=2,
    )
    async with Cell(actions=[outer]) as robot:
        robot.jams = 0
        robot.state.done = False
        handle = robot.outer()
        await robot.sleep(3)
        robot.state.done = True
        assert await handle == "end"
        assert robot.state.outer_history == (
            "run -> rest: succeeded",
            "rest -> end: done becomes=True",
        )
        assert robot.state.inner_state == "end"


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_unknown_key_is_refused_when_it_starts() -> None:
    machine = StateMachine("m", {"a": Cell.idle, "b": None}, [("a", "b", When("dorr", value=1))])
    async with Cell() as robot:
        robot.state.door = 0
        handle = machine(robot)
        with pytest.raises(UnknownStateKeyError, match="dorr"):
            await handle
        assert robot.notes == []  # no state ran


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_a_state_that_starts_no_action_is_an_error() -> None:
    machine = StateMachine("m", {"a": lambda robot: "nothing"}, [])
    async with Robot() as robot:
        with pytest.raises(StateMachineError, match=r"^state 'a': .* returned 'nothing', not the"):
            await machine(robot)


BAD: list[tuple[dict[str, Any], list[Any], dict[str, Any], str]] = [
    (
        {"a": Cell.idle},
        [("a", "b", S)],
        {},
        "transition 'a' -> 'b' of 'm': unknown state 'b'; declared states: ['a']",
    ),
    (
        {"a": Cell.idle},
        [("x", "a", S)],
        {},
        "transition 'x' -> 'a' of 'm': unknown state 'x'; declared states: ['a'] "
        "(or '*' as the source: any state)",
    ),
    (
        {"a": Cell.idle},
        [("a", "*", S)],
        {},
        "transition 'a' -> '*' of 'm': unknown state '*'; declared states: ['a']",
    ),
    (
        {"a": Cell.idle, "b": None},
        [("b", "a", S)],
        {},
        "transition 'b' -> 'a' of 'm': 'b' is a final state (no action); no transition leaves it",
    ),
    (
        {"a": Cell.idle, "b": None, "c": None},
        [("a", "b", F), ("a", "c", F)],
        {},
        "two transitions of 'm' leave 'a' on FAILED: to 'b' and to 'c'; keep one",
    ),
    (
        {"a": Cell.idle},
        [("a", "a", Outcome.NOT_DONE)],
        {},
        "transition 'a' -> 'a' of 'm': the trigger must be an Outcome (SUCCEEDED, FAILED, "
        "CANCELLED, SKIPPED) or When(key, **condition), got <Outcome.NOT_DONE: 'not_done'>",
    ),
    (
        {"a": Cell.idle},
        [("a", "a", "bumper")],
        {},
        "transition 'a' -> 'a' of 'm': the trigger must be an Outcome (SUCCEEDED, FAILED, "
        "CANCELLED, SKIPPED) or When(key, **condition), got 'bumper'",
    ),
    (
        {"a": Cell.idle},
        [("a", "a")],
        {},
        "transition ('a', 'a') of 'm': give (source, target, trigger)",
    ),
    (
        {"a": Cell.idle},
        [],
        {"initial": "z"},
        "initial state 'z' of 'm' is not declared; states: ['a']",
    ),
    (
        {"a": 42},
        [],
        {},
        "state 'a' of 'm' is 42: give an @action, a bound action, a function of the robot "
        "returning an action's handle, or None (final)",
    ),
    (
        {"*": Cell.idle},
        [],
        {},
        "StateMachine 'm': a state name must be a non-empty string, not '*'",
    ),
    (
        {},
        [],
        {},
        "StateMachine 'm' needs states: a mapping of state names to actions (None for a final "
        "state), got {}",
    ),
    (
        {"a": Cell.idle},
        [],
        {"history": 0},
        "StateMachine 'm': history must be a positive int, got 0",
    ),
]


@pytest.mark.parametrize(("states", "transitions", "options", "message"), BAD)
def test_a_malformed_machine_is_refused_when_built(
    states: dict[str, Any], transitions: list[Any], options: dict[str, Any], message: str
) -> None:
    with pytest.raises(StateMachineError, match=f"^{re.escape(message)}$"):
        StateMachine("m", states, transitions, **options)


def test_a_malformed_condition_is_refused_when_built() -> None:
    with pytest.raises(InvalidConditionError, match="no condition"):
        When("bumper")
    with pytest.raises(InvalidConditionError, match="give only one"):
        When("bumper", becomes=True, value=False)  # type: ignore[call-arg]
    with pytest.raises(InvalidConditionError, match="held_for"):
        When("bumper", becomes=True, held_for=-1)
    with pytest.raises(StateMachineError, match=r"^When\(\) watches a state key or a predicate"):
        When(42)  # type: ignore[arg-type]
    assert repr(When("ir", below=0.2, held_for=0.5)) == "When('ir', below=0.2, held_for=0.5)"


def test_it_needs_a_name() -> None:
    with pytest.raises(StateMachineError, match="needs a name"):
        StateMachine("", {"a": Cell.idle}, [])
    assert repr(CELL) == "<StateMachine cell states=['work', 'repair', 'idle', 'off']>"
    assert (CELL.state_key, CELL.history_key) == ("cell_state", "cell_history")
