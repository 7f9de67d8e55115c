"""Each disturbance does what it says on FakeBase, at the time or boundary it is given."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio import ActionInterrupted, action
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    Cancel,
    Cliff,
    EmergencyStop,
    Hit,
    On,
    Pause,
    Preempt,
    Reading,
    Scenario,
    Silence,
    StaleOdometry,
)

if TYPE_CHECKING:
    from pyrobots_aio.testing.explore import Disturbance

TIMES = (0.9, 1.05, 1.3, 1.6)  # before the hit at 1.0, after it, late in a 0.5 s hold, after it


@action
async def nap(robot: FakeBase, seconds: float) -> None:
    await robot.sleep(seconds)


def _probe(what: Disturbance, look: Any) -> list[object]:
    """``look(robot)`` at each of `TIMES`, the disturbance coming at t=1.0 (driving at 0.1 m/s)."""
    seen: list[object] = []

    async def behaviour(robot: FakeBase) -> None:
        robot.drive(0.1, 0.0)
        for time in TIMES:
            await robot.sleep(time - robot.time())
            seen.append(look(robot))

    run = Scenario(behaviour, base=FakeBase, invariants=[]).run([Hit(what, At(1.0))])
    assert (run.violations, run.error) == ([], None)
    return seen


@pytest.mark.parametrize(
    ("what", "key", "expected"),
    [
        (Bump("left", hold=0.5), "bumper_left", [False, True, True, False]),
        (Bump("right", hold=0.5), "bumper_left", [False, False, False, False]),
        (Bump(hold=0.5), "bumper", [False, True, True, False]),
        (Bump(), "bumper", [False, False, False, False]),  # the next tick (1.02) released it
        (Cliff("side_right", hold=0.5), "cliff_side_right", [False, True, True, False]),
        (Reading("left", 0.05, hold=0.5), "ir_left", [0.4, 0.05, 0.05, 0.4]),
    ],
)
def test_readings_are_pressed_and_held(what: Disturbance, key: str, expected: list[object]) -> None:
    assert _probe(what, lambda robot: robot.state[key]) == expected


def test_the_world_is_read_through_the_tamper_only_while_something_is_held() -> None:
    seen: list[tuple[bool, object]] = []

    async def behaviour(robot: FakeBase) -> None:
        robot.drive(0.1, 0.0)
        for time in (0.9, 1.05, 1.3, 1.55, 1.9):
            await robot.sleep(time - robot.time())
            seen.append(("read_sensors" in vars(robot.world), robot.state["bumper"]))

    hits = [Hit(Bump(hold=0.2), At(1.0)), Hit(Bump(hold=0.2), At(1.5))]
    run = Scenario(behaviour, base=FakeBase, invariants=[]).run(hits)
    assert (run.violations, run.error) == ([], None)
    # shadowed from the first hold, given back once it ended, shadowed again by the second
    assert seen == [(False, False), (True, True), (False, False), (True, True), (False, False)]


def test_a_silent_sensor_keeps_its_last_value_while_the_others_go_on() -> None:
    seen = _probe(
        Silence("ir_left", 0.5),
        lambda robot: (robot.state.version("ir_right"), robot.state.version("ir_left")),
    )
    (right, _), *_ = seen
    assert [r - right for r, _ in seen] == [0, 7, 20, 35]  # a write every 0.02 s
    assert seen[1][1] == seen[2][1] < seen[3][1]


def test_stale_odometry_stands_still_while_the_robot_moves() -> None:
    seen = _probe(StaleOdometry(0.5), lambda robot: (robot.odom_pose()[0], robot.map_pose()[0]))
    odom = [round(x, 3) for x, _ in seen]
    truth = [round(x, 3) for _, x in seen]
    assert odom[1] == odom[2] != odom[3]
    assert truth[1] < truth[2] < truth[3]


def test_the_emergency_stop_latches_and_clears() -> None:
    seen = _probe(EmergencyStop(clear_after=0.5), lambda robot: robot.emergency_stopped)
    assert seen == [False, True, True, False]


def _outcome(what: Disturbance, when: On | At) -> tuple[str, float]:
    async def behaviour(robot: FakeBase) -> tuple[str, float]:
        try:
            await nap(robot, 2.0)
        except ActionInterrupted:
            return "interrupted", robot.time()
        return "slept", robot.time()

    run = Scenario(behaviour, base=FakeBase, invariants=[]).run([Hit(what, when)])
    return run.result  # type: ignore[return-value]


def test_pause_freezes_the_actions_for_its_seconds() -> None:
    assert _outcome(Pause(1.0), At(0.5)) == ("slept", 3.0)


def test_cancel_ends_the_action_named() -> None:
    assert _outcome(Cancel("nap"), On("nap")) == ("interrupted", 0.0)
    assert _outcome(Cancel("other"), On("nap")) == ("slept", 2.0)


def test_preempt_takes_the_wheels_from_a_motion() -> None:
    async def behaviour(robot: FakeBase) -> str:
        try:
            await robot.drive_distance(1.0)
        except ActionInterrupted as stop:
            return str(stop.reason)
        return "drove"

    run = Scenario(behaviour, base=FakeBase, invariants=[]).run([Hit(Preempt(), At(1.0))])
    assert "preempting_reflex" in str(run.result)


def test_printed_values_are_the_code_that_builds_them() -> None:
    assert repr(Hit(Bump("left", hold=0.5), On("dock", nth=2, at="end"))) == (
        "Hit(Bump('left', hold=0.5), On('dock', nth=2, at='end'))"
    )
    assert repr([Bump(), Cliff(), EmergencyStop(None), Cancel(), At(1.25)]) == (
        "[Bump(), Cliff(), EmergencyStop(None), Cancel(), At(1.25)]"
    )
