"""Master controller: a plan run by a state machine, with retries, a health monitor and an e-stop.

The executive of a humanoid's integration module, built from the supervision
parts instead of hand-written loops: a `StateMachine` runs the phases (the
plan; after a fault, the recovery to a safe pose); flaky steps are `retry`-ed
with exponential backoff, the walk under a `timeout` too; a `HealthMonitor`
watches the camera stream. When the stream is lost, the emergency stop cuts
the motors and ends the plan where it stands: the walk has slipped and its
retry is waiting out its backoff, holding no limb, yet it is stopped and
never walks again; the machine takes its failure path, the recovery.
While the stop is latched, the steps refuse to move (as a `DriveBase`
refuses motion), and a stop during the recovery starts it again.
`supervise` is the controller of a running humanoid: the behaviour that
tests/examples/test_master_controller_explore.py explores.

Run: ``python examples/master_controller.py``
"""

from __future__ import annotations

import asyncio
import itertools
import logging
from typing import TYPE_CHECKING

from pyrobots_aio import (
    CompoundResource,
    EmergencyStopError,
    HealthMonitor,
    Outcome,
    Resource,
    Robot,
    StateMachine,
    action,
    exponential,
    lock,
    retry,
    timeout,
)
from pyrobots_aio.cli import install_console_handler

if TYPE_CHECKING:
    from collections.abc import Iterable

    from pyrobots_aio import Instrument

ARMS, LEGS = Resource("arms"), Resource("legs")
BODY = CompoundResource(ARMS, LEGS, name="body")
PLAN = ("grasp_cup", "lift", "walk_to_table", "grasp_cup")
CAMERA_RATE = 30.0  # Hz the camera publishes at, until its driver crashes

log = logging.getLogger("master_controller")


class Humanoid(Robot):
    """A pretend humanoid: its steps only take time; ``lift`` fails twice, the walk slips."""

    def __init__(self, instruments: Iterable[Instrument] = ()) -> None:
        super().__init__(dummy=True, instruments=instruments)
        self.lift_attempts = self.walk_attempts = 0
        self.report: list[str] = []

    def note(self, line: str) -> None:
        """Add a line to the report (and log it, with the time and the action)."""
        self.report.append(line)
        log.info("%s", line)

    def halt_actuators(self) -> None:
        self.state.motors = False  # the emergency stop cuts the motors first
        super().halt_actuators()

    async def move(self, step: str, seconds: float) -> None:
        """Move the limbs for ``seconds``: refused while the emergency stop is latched.

        As a `DriveBase` refuses motion: a step that starts under the stop (the
        camera was lost before the plan began) fails, and the plan with it.
        """
        if self.emergency_stop_reason is not None:
            raise EmergencyStopError(step, self.emergency_stop_reason)
        await self.sleep(seconds)

    @action
    @lock(ARMS)
    async def grasp_cup(self) -> str:
        await self.move("grasp_cup", 0.3)
        return "cup grasped"

    @retry(4, backoff=exponential(0.1, factor=2))  # 0.1 s, 0.2 s, 0.4 s between attempts
    @action
    @lock(ARMS)
    async def lift(self) -> str:
        self.lift_attempts += 1
        await self.move("lift", 0.2)
        if self.lift_attempts < 3:
            raise RuntimeError(f"arm controller timeout (attempt {self.lift_attempts})")
        return f"cup lifted (attempt {self.lift_attempts})"

    @retry(3, backoff=exponential(1.0, factor=2))  # 1 s, then 2 s between attempts
    @timeout(10)
    @action
    @lock(LEGS)
    async def walk_to_table(self) -> str:
        self.walk_attempts += 1
        await self.move("walk_to_table", 1.0)
        if self.walk_attempts == 1:
            raise RuntimeError("slipped on the rug")
        await self.move("walk_to_table", 4.0)
        return "at the table"

    @action
    @lock(BODY)
    async def go_to_safe_pose(self) -> str:
        await self.sleep(0.5)
        self.state.pose = "safe"
        return "safe pose"


@action
async def execute_plan(robot: Humanoid) -> None:
    """Run the plan's steps in turn: a step that fails, or is stopped, fails the plan."""
    for step in PLAN:
        robot.note(f"{step}: {await getattr(robot, step)()}")


@action
async def recover(robot: Humanoid) -> None:
    """After a fault: say what stopped the robot, then take the safe pose."""
    robot.note(f"fault ({robot.emergency_stop_reason}): {status(robot)}")
    robot.note(await robot.go_to_safe_pose())


MASTER = StateMachine(
    "master",
    {"plan": execute_plan, "recover": recover, "done": None, "safe": None},
    [
        ("plan", "done", Outcome.SUCCEEDED),
        ("plan", "recover", Outcome.FAILED),
        ("recover", "safe", Outcome.SUCCEEDED),
        ("recover", "recover", Outcome.FAILED),  # a stop during the recovery: recover again
    ],
)


def status(robot: Humanoid) -> str:
    """Which limbs are held, and whether the motors are on."""
    held = ", ".join(sorted(r.name for r in robot.resources.held())) or "no limb"
    return f"{held} in use, motors {'on' if robot.state.motors else 'off'}"


@action
async def camera(robot: Humanoid, frames: int | None) -> None:
    """The camera driver: 30 Hz, until it crashes after ``frames`` frames (None: it does not)."""
    for _ in itertools.count() if frames is None else range(frames):
        robot.state.camera = robot.time()
        await asyncio.sleep(1 / CAMERA_RATE)


async def supervise(robot: Humanoid, camera_frames: int | None = 75) -> list[str]:
    """The master controller of a running humanoid, its camera crashing after ``camera_frames``.

    Returns the report; it ends with the phase the machine ended in.
    """
    robot.state.update(camera=0.0, motors=True, pose="home")
    driver = camera(robot, camera_frames)  # a background action, beside the plan
    health = HealthMonitor(robot)
    health.watch("camera", warn_after=0.1, stale_after=0.5)
    health.start()
    robot.whenever("health_camera", becomes="stale").do(robot.emergency_stop, "camera lost")
    phase = await MASTER(robot)
    driver.cancel("the plan is over")  # (75 frames: it has crashed by then)
    await driver.wait_done()
    pose, camera_health = robot.state.pose, robot.state.health
    robot.note(f"{phase}: pose {pose}, camera {camera_health}, {status(robot)}")
    return robot.report


async def main(instruments: Iterable[Instrument] = ()) -> list[str]:
    async with Humanoid(instruments) as robot:
        return await supervise(robot)


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    asyncio.run(main())
