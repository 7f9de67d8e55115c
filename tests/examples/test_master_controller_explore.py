"""The master controller example, explored: stops, pauses, cancels, a lost camera, a reflex.

The behaviour is the example's own `supervise` on a fresh `Humanoid`, its
camera not crashing by itself (the plan can end ``done``). Disturbances that
make sense for a humanoid with no wheels nor bumper: the emergency stop
(cleared or not), pause/resume, a cancel, its camera's driver hanging (a
silent sensor, which the health monitor must turn into a stop) or crashing
(a cancel of ``camera``), and a reflex that preempts the arms. Invariants: no
action outlives the robot, no limb held twice, the humanoid's own version of
"wheels still while the e-stop is latched" (no limb held by anything but the
recovery), and the example's outcome: the plan done, or the humanoid safe.

Each schedule below is one that exploring found breaking the example, shrunk
and printed by `Scenario.explore`; the example is fixed.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any

import pytest
from hypothesis import strategies as st
from test_examples import load_example

from pyrobots_aio import ActionInterrupted, ExecEvent, ResourceAcquired, action, lock
from pyrobots_aio.testing.explore import (
    At,
    Cancel,
    Disturbance,
    EmergencyStop,
    Hit,
    Invariant,
    On,
    Pause,
    Run,
    Scenario,
    Target,
    no_action_outlives_robot,
    no_resource_held_twice,
)

if TYPE_CHECKING:
    from collections.abc import Callable

    from pyrobots_aio import Robot

example: ModuleType = load_example("master_controller")
Humanoid = example.Humanoid


@dataclass(frozen=True, slots=True, repr=False)
class CameraHangs(Disturbance):
    """The camera's driver hangs for ``seconds`` (its action paused): no frame meanwhile."""

    seconds: float = 1.0

    def apply(self, target: Target) -> None:
        for handle in target.robot.handles():
            if handle.name == "camera" and handle.pause("explore: CameraHangs"):
                target.later(self.seconds, handle.resume)


@action
@lock(example.ARMS, priority=1000, preempt=True)
async def catch_falling_cup(robot: Any, seconds: float) -> None:
    await robot.move("catch_falling_cup", seconds)


@dataclass(frozen=True, slots=True, repr=False)
class Catch(Disturbance):
    """A reflex takes the arms from whoever holds them (``preempt=True``) for ``seconds``."""

    seconds: float = 0.5

    def apply(self, target: Target) -> None:
        catch_falling_cup(target.robot, self.seconds)


class limbs_still_while_stopped(Invariant):
    """Once the stop has latched for ``grace`` seconds, only the recovery holds a limb.

    The humanoid's "wheels still while the e-stop is latched": looked at
    ``grace`` after each stop, and after each limb taken under one.
    """

    def __init__(self, grace: float = 0.01) -> None:
        self.grace = grace

    def watch(self, robot: Robot, fail: Callable[[str], None]) -> None:
        loop, seen = asyncio.get_running_loop(), set[int]()

        def look() -> None:
            for limb in (example.ARMS, example.LEGS) if robot.emergency_stopped else ():
                owner = robot.resources.owner(limb)
                if owner is not None and owner.name != "go_to_safe_pose" and owner.id not in seen:
                    seen.add(owner.id)
                    fail(
                        f"at t={robot.time():.3f} {owner.name} #{owner.id} held {limb.name!r} "
                        f"under the emergency stop"
                    )

        def soon(_: object = None) -> tuple[()]:
            loop.call_later(self.grace, look)
            return ()

        class Taken:
            def on_event(self, event: ExecEvent) -> None:
                if isinstance(event, ResourceAcquired) and robot.emergency_stopped:
                    soon()

        robot.add_emergency_stop_callback(soon)
        robot.instruments.add(Taken())


def plan_done_or_safe(run: Run[Any]) -> None:
    """The machine ends ``done`` (every step of the plan made) or ``safe`` (the safe pose taken).

    Unless something of the plan was cancelled from outside: then awaiting it says so.
    """
    if run.error is not None:
        assert isinstance(run.error, ActionInterrupted), f"the controller raised {run.error!r}"
        assert run.error.reason == "explore: Cancel", f"the controller raised {run.error!r}"
        return
    *steps, last = run.result  # type: ignore[misc]
    phase = last.split(":")[0]
    assert phase in {"done", "safe"}, f"the controller ended {last!r}"
    if phase == "done":
        assert [line.split(":")[0] for line in steps] == list(example.PLAN), steps
    assert (run.robot.state.pose == "safe") == (phase == "safe"), (last, run.robot.state.pose)


async def supervise(robot: Any) -> list[str]:
    return await example.supervise(robot, camera_frames=None)  # type: ignore[no-any-return]


STEPS = ("grasp_cup", "lift", "walk_to_table", "go_to_safe_pose", "execute_plan", "recover")

MASTER = Scenario(
    supervise,
    base=Humanoid,
    disturbances=[
        EmergencyStop,
        EmergencyStop(None),
        Pause,
        Cancel,
        st.builds(CameraHangs, st.sampled_from((0.2, 1.0))),
        st.builds(Catch, st.sampled_from((0.1, 1.0))),
    ],
    boundaries=(*STEPS, "camera"),
    invariants=[
        plan_done_or_safe,
        limbs_still_while_stopped(),
        no_action_outlives_robot(),
        no_resource_held_twice(),
    ],
    horizon=10.0,  # the undisturbed plan takes 8.5 s
    time_limit=60.0,
    name="master",
)


@pytest.mark.explore(examples=100)
def test_the_master_controller_ends_done_or_safe_whatever_hits_it(
    explore: Callable[[Scenario[Any]], None],
) -> None:
    explore(MASTER)


def test_a_stop_before_the_plan_starts_refuses_its_steps() -> None:
    # found by exploring: a stop latched as the machine started (the camera lost before the
    # plan began) preempted nothing, and the humanoid's steps, which did not look at the
    # stop, carried out the whole plan under it: "done", motors off
    run = MASTER.replay([
        Hit(EmergencyStop(None), At(0.0)),
    ])  # fmt: skip
    assert run.result[-1] == "safe: pose safe, camera ok, no limb in use, motors off"  # type: ignore[index]


def test_a_stop_during_the_recovery_recovers_again() -> None:
    # found by exploring: the recovery had no FAILED transition, so a stop while it took the
    # safe pose ended the machine with EmergencyStopError, the humanoid not safe
    run = MASTER.replay([
        Hit(EmergencyStop(0.5), At(0.0)),
        Hit(EmergencyStop(0.5), On('go_to_safe_pose')),
    ])  # fmt: skip
    assert run.robot.state.master_history[-2:] == (
        "recover -> recover: emergency stop: explore: EmergencyStop",
        "recover -> safe: succeeded",
    )
