"""The motion actions themselves, explored: each ends stopped, and says why if it did not arrive.

The random walk's exploration (test_walk_explore.py) reaches the motions only
as the walk calls them (never ``navigate_to`` on its own); here a plan calls
each, in turn, and carries on whatever became of the one before. Drawn: every
shipped disturbance, at the motions' starts and ends and at virtual times.
Invariants: each motion ends SUCCEEDED, having got where it was sent, or fails
with a `MotionError` (a stall, a refused motion, a failed docking) or the
`ActionInterrupted` of a motion it ran, or is cancelled with a reason; the
wheels are stopped when it ends; no run hangs (the time limit), and the
shipped invariants but `no_forward_into_bumper` (no reflex here: a bare
motion drives on into a pressed bumper, the bumper is the reflex's business).

On `FakeBase`, and a few examples on `SimRobot`, where the invariants read
the wheels' command from the simulated world, not the odometry's speeds.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, cast

import pytest

from pyrobots_aio import (
    ActionFinished,
    ActionInterrupted,
    ActionSpawned,
    ExecEvent,
    MotionError,
    Outcome,
)
from pyrobots_aio.motion import ANGLE_TOLERANCE, DISTANCE_TOLERANCE, DriveBase
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    Cancel,
    Cliff,
    EmergencyStop,
    Hit,
    Invariant,
    On,
    Pause,
    Preempt,
    Reading,
    Run,
    Scenario,
    Silence,
    StaleOdometry,
    completes,
    no_action_outlives_robot,
    no_forward_into_bumper,
    no_resource_held_twice,
    still_while_stopped,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    from pyrobots_aio import ActionHandle, Robot

    Check = Callable[[Any], bool]

MOTIONS = ("undock", "drive_distance", "rotate_angle", "navigate_to", "dock")
TARGET = (0.5, 1.0, 0.0)
"""Where ``navigate_to`` goes: in the open, on either base's floor."""


class motions_end_stopped_saying_why(Invariant):
    """Each motion ends with the wheels stopped; a failure is a motion's, and says why."""

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        world = cast("FakeBase | SimRobot", robot).world
        handles: dict[int | None, ActionHandle[Any]] = {}

        def why_not(handle: ActionHandle[Any]) -> str | None:
            if handle.outcome is Outcome.CANCELLED:
                return None if handle.cancel_reason else "was cancelled with no reason"
            error = handle.exception() if handle.outcome is Outcome.FAILED else None
            if error is None or (isinstance(error, MotionError) and str(error)):
                return None
            if isinstance(error, ActionInterrupted) and error.reason:
                return None  # a motion it ran was cancelled (undock's drive, dock's way there)
            return f"failed with {error!r}"

        class Ends:
            def on_event(self, event: ExecEvent) -> None:
                if event.name not in MOTIONS:
                    return
                if isinstance(event, ActionSpawned):
                    (handles[event.action],) = [h for h in robot.handles() if h.id == event.action]
                elif isinstance(event, ActionFinished):
                    handle, at = handles.pop(event.action), f"at t={event.time:.3f}"
                    what = f"{event.name} #{event.action}"
                    if world.command != (0.0, 0.0):
                        fail(f"{at} {what} ended with the wheels commanded {world.command}")
                    if (why := why_not(handle)) is not None:
                        fail(f"{at} {what} {why}")

        robot.instruments.add(Ends())


class parked_while_paused(Invariant):
    """A paused motion has the wheels stopped within ``grace`` seconds (DESIGN §13)."""

    def __init__(self, grace: float = 0.05) -> None:
        self.grace = grace

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        world = cast("FakeBase | SimRobot", robot).world
        since: list[float] = []  # when motions were first seen paused, while they are

        def look(_: object) -> None:
            paused = [h for h in robot.handles() if h.name in MOTIONS and h.paused]
            if not paused:
                since.clear()
                return
            now = robot.time()
            since[:] = since or [now]
            if now - since[0] > self.grace + 1e-9 and world.command != (0.0, 0.0):
                what = f"{paused[0].name} #{paused[0].id}"
                fail(f"at t={now:.3f} the wheels were commanded {world.command} with {what} paused")

        robot.state.subscribe(look, ("v", "w"))  # each tick


def _went(goal: float) -> Check:
    return lambda distance: abs(distance - goal) <= DISTANCE_TOLERANCE


def _turned_to(goal: float) -> Check:
    return lambda turned: abs(turned - goal) <= ANGLE_TOLERANCE


def _arrived(robot: DriveBase) -> bool:
    x, y, yaw = robot.map_pose()
    near = math.dist((x, y), TARGET[:2]) <= 5 * DISTANCE_TOLERANCE  # navigate_to's own
    return near and abs(math.remainder(yaw - TARGET[2], math.tau)) <= ANGLE_TOLERANCE


def plan(robot: DriveBase) -> list[tuple[str, Callable[[], ActionHandle[Any]], Check]]:
    """Each motion, how to start it, and what its result (or the robot) is if it arrived."""
    return [
        ("undock", robot.undock, lambda _: not robot.state.docked),
        ("drive_distance", lambda: robot.drive_distance(0.8), _went(0.8)),
        ("rotate_angle", lambda: robot.rotate_angle(2.5), _turned_to(2.5)),
        ("navigate_to", lambda: robot.navigate_to(TARGET), lambda _: _arrived(robot)),
        ("rotate_angle", lambda: robot.rotate_angle(-1.0), _turned_to(-1.0)),
        ("dock", robot.dock, lambda _: robot.state.docked),
    ]


async def motions(robot: DriveBase) -> list[str]:
    """Run the plan's motions in turn, whatever became of each; say how each ended."""
    ends = []
    for name, start, arrived in plan(robot):
        handle = start()
        outcome = await handle.wait_done()
        if outcome is Outcome.SUCCEEDED and not arrived(handle.result()):
            ends.append(f"{name} succeeded short of its goal (result {handle.result()!r})")
        else:
            ends.append(f"{name} {outcome.value}")
    return ends


def succeeded_where_sent(run: Run[Any]) -> None:
    """Every motion that succeeded got where it was sent."""
    short = [end for end in run.result if "short" in end]  # type: ignore[attr-defined]
    assert not short, short


def scenario(base: Callable[[], DriveBase], name: str = "motions") -> Scenario[Any]:
    """The motions on ``base``; a scenario's ``name`` seeds its ``ci`` examples."""
    return Scenario(
        motions,
        base=base,
        disturbances=[
            Bump,
            Cliff,
            Reading,
            Silence,
            StaleOdometry,
            Pause,
            Cancel,
            EmergencyStop,
            EmergencyStop(None),
            Preempt,
        ],
        boundaries=MOTIONS,
        invariants=[
            completes(),
            succeeded_where_sent,
            motions_end_stopped_saying_why(),
            parked_while_paused(),
            still_while_stopped(),
            no_action_outlives_robot(),
            no_resource_held_twice(),
        ],
        horizon=45.0,  # the undisturbed plan takes 44 s
        time_limit=120.0,
        name=name,
    )


def test_the_undisturbed_plan_arrives_everywhere() -> None:
    run = scenario(FakeBase).replay([])
    assert run.result == [
        "undock succeeded",
        "drive_distance succeeded",
        "rotate_angle succeeded",
        "navigate_to succeeded",
        "rotate_angle succeeded",
        "dock succeeded",
    ]


@pytest.mark.explore(examples=25)
def test_each_motion_ends_stopped_and_arrives_or_says_why_on_fakebase(
    explore: Callable[[Scenario[Any]], None],
) -> None:
    explore(scenario(FakeBase))


@pytest.mark.explore(examples=5)
def test_each_motion_ends_stopped_and_arrives_or_says_why_on_simrobot(
    explore: Callable[[Scenario[Any]], None],
) -> None:
    explore(scenario(SimRobot, name="sim_motions"))  # other schedules than FakeBase's


# -- on SimRobot, the invariants read the wheels' command, not the odometry's speeds ----------


def _violations(
    behaviour: Callable[[SimRobot], Awaitable[None]], invariant: Invariant, *hits: Hit
) -> list[str]:
    return Scenario(behaviour, base=SimRobot, invariants=[invariant]).run(hits).violations


def test_on_simrobot_turning_in_place_into_a_held_bump_is_not_driving_forward() -> None:
    # read from the odometry's speeds, v was a hair above zero as the robot turned in place,
    # and no_forward_into_bumper took that for driving forward into the bump
    async def turn(robot: SimRobot) -> None:
        await robot.undock()
        await robot.rotate_angle(3.0)

    bump = Hit(Bump(hold=2.0), On("rotate_angle"))
    assert _violations(turn, no_forward_into_bumper(), bump) == []


def test_on_simrobot_still_while_stopped_sees_the_command_not_the_noise() -> None:
    async def rogue(robot: SimRobot) -> None:
        await robot.sleep(1.0)
        robot.backend.set_velocity(0.1, 0.0)  # past the executive, under the stop
        await robot.sleep(1.0)

    # the odometry's speeds of the docked robot are noise about zero: read as the command, the
    # stop was broken at t=0.560 already; the command is broken at the first tick after 1 s
    stop = Hit(EmergencyStop(clear_after=None), At(0.5))
    assert _violations(rogue, still_while_stopped(), stop) == [
        "at t=1.020 the wheels were commanded (v=0.100, w=0.000) under the emergency stop "
        "latched since t=0.500"
    ]
