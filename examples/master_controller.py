"""Master controller: a plan executed as actions, with retries, e-stop and a health monitor.

The executive of a humanoid's integration module: each plan step is an action;
a step that fails is retried with exponential backoff; a health monitor flags
a sensor stream whose rate drops; pressing the emergency stop cancels every
other action, disables the motors and returns the robot to a safe state.

Run: ``python examples/master_controller.py``
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING

from pyrobots_aio import ActionInterrupted, Robot, action
from pyrobots_aio.actions import current_action
from pyrobots_aio.cli import install_console_handler

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Iterable

    from pyrobots_aio import Instrument

RETRIES = 4
BACKOFF = 0.1  # seconds before the first retry; doubled each time
CAMERA_RATE = 30.0  # Hz the camera should publish at
MIN_RATE = 20.0  # below this, the stream is flagged

log = logging.getLogger("master_controller")


class Humanoid(Robot):
    """A pretend humanoid: its steps only take time; ``lift`` fails twice, then works."""

    def __init__(self, instruments: Iterable[Instrument] = ()) -> None:
        super().__init__(dummy=True, instruments=instruments)
        self.lift_attempts = 0
        self.report: list[str] = []

    def note(self, line: str) -> None:
        """Add a line to the report (and log it, with the time and the action)."""
        self.report.append(line)
        log.info("%s", line)

    @action
    async def grasp_cup(self) -> str:
        await self.sleep(0.3)
        return "cup grasped"

    @action
    async def lift(self) -> str:
        self.lift_attempts += 1
        await self.sleep(0.2)
        if self.lift_attempts < 3:
            raise RuntimeError(f"arm controller timeout (attempt {self.lift_attempts})")
        return "cup lifted"

    @action
    async def walk_to_table(self) -> str:
        await self.sleep(5.0)
        return "at the table"

    @action
    async def go_to_safe_pose(self) -> str:
        await self.sleep(0.5)
        self.state.pose = "safe"
        return "safe pose"


@action
async def run_step(robot: Humanoid, step: str) -> str:
    """Run one plan step, retrying a failure with exponential backoff."""
    attempt: Callable[[], Awaitable[str]] = getattr(robot, step)
    delay = BACKOFF
    for _ in range(RETRIES - 1):
        try:
            return await attempt()
        except ActionInterrupted:
            raise
        except Exception as error:
            robot.note(f"{step} failed ({error}); retrying in {delay:.1f} s")
            await robot.sleep(delay)
            delay *= 2
    return await attempt()  # the last attempt: its failure is the step's


@action
async def execute_plan(robot: Humanoid, plan: list[str]) -> list[str]:
    """Execute the plan step by step; stop at the first step that cannot be done."""
    done = []
    for step in plan:
        try:
            done.append(await run_step(robot, step))
        except ActionInterrupted as stop:
            robot.note(f"plan stopped during {step}: {stop.reason}")
            break
        robot.note(f"{step}: {done[-1]}")
    return done


@action
async def health_monitor(robot: Humanoid, period: float = 0.5) -> None:
    """Flag the camera stream when its publishing rate drops below MIN_RATE."""
    last = robot.state.version("camera")
    while True:
        await robot.sleep(period)
        now = robot.state.version("camera")
        rate, last = (now - last) / period, now
        healthy = rate >= MIN_RATE
        if healthy != robot.state.camera_ok:
            robot.state.camera_ok = healthy
            robot.note(f"camera stream {'recovered' if healthy else 'degraded'}: {rate:.0f} Hz")


@action
async def emergency_stop(robot: Humanoid) -> None:
    """Cancel everything else, cut the motors, return to the safe pose."""
    robot.state.motors = False
    await robot.cancel_all_others("emergency stop")
    me = current_action.get()
    robot.note(f"e-stop: {status(robot, but=me.id if me else None)}")
    robot.note(await robot.go_to_safe_pose())


def status(robot: Humanoid, but: int | None = None) -> str:
    """What still runs (leaving out action ``but``) and whether the motors are on."""
    running = ", ".join(f"{i.name}#{i.id}" for i in robot.running() if i.id != but)
    actions = f"still running: {running}" if running else "nothing running"
    return f"{actions}, motors {'on' if robot.state.motors else 'off'}"


async def camera(robot: Humanoid, degrade_at: float) -> None:
    """The camera driver: 30 Hz, then 5 Hz after ``degrade_at`` seconds."""
    start = robot.time()
    while True:
        rate = CAMERA_RATE if robot.time() - start < degrade_at else 5.0
        robot.state.camera = robot.time()
        await asyncio.sleep(1 / rate)


async def main(instruments: Iterable[Instrument] = ()) -> list[str]:
    async with Humanoid(instruments) as robot:
        robot.state.update(camera=0.0, camera_ok=True, motors=True, estop=False, pose="home")
        driver = asyncio.create_task(camera(robot, degrade_at=1.5))
        robot.on("estop", becomes=True).do(emergency_stop)
        health_monitor(robot)
        plan = execute_plan(robot, ["grasp_cup", "lift", "walk_to_table", "grasp_cup"])
        await robot.sleep(3.0)
        robot.state.estop = True  # someone hits the red button mid-walk
        try:
            await plan
        except ActionInterrupted as stop:
            robot.note(f"plan interrupted: {stop.reason}")
        await robot.sleep(1.0)
        driver.cancel()
        await asyncio.gather(driver, return_exceptions=True)
        robot.note(f"pose {robot.state.pose}, {status(robot)}")
        return robot.report


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    asyncio.run(main())
