"""The Create 3 random walk with a bumper reflex, done right.

The hobbyist ROS 2 script this follows undocks, drives out, makes ten random
turns and drives, and docks; its bumper reflex cancelled the current goal, and
control never came back to the walk. Here the reflex is an action that locks
the wheels with a higher priority and ``preempt=True``: the current motion is
cancelled (its cleanup stops the wheels), the reflex backs off and turns away,
and the walk — which sees `ActionInterrupted`, an ordinary exception — simply
goes on with its next move once the reflex has released the wheels. So it
does wherever the bump comes: while undocking, in the first drive, while
docking (the tests press the bumper at each action boundary of a walk with
`pyrobots_aio.testing.inject_bump`).

With ``random_walk(robot, on_bump="suspend")`` the reflex is
`suspending_reflex`, which locks with ``preempt="suspend"`` instead: the
current motion is frozen where it stands (its pause hook parks the wheels),
the reflex borrows the wheels, and the motion resumes with its remaining
distance or angle once the reflex is done; no move is interrupted. A dock
suspended while reversing onto the dock lines up in front of it again (the
reflex moved it off its line), so the walk docks in either mode.

It is written against `pyrobots_aio.motion.DriveBase` alone, so it runs
unchanged on the simulated robot, a ROS 2 robot and the in-memory
`pyrobots_aio.testing.FakeBase`; importing it needs no MuJoCo. Run it with
``pyrobots-aio demo random-walk`` or ``python examples/random_walk.py``.
"""

from __future__ import annotations

import logging
import math
import random
from dataclasses import dataclass
from typing import Literal

from .._exceptions import ActionInterrupted, StallError
from ..actions import action, lock
from ..motion import WHEELS, DriveBase

__all__ = [
    "BACK_OFF",
    "DETOUR",
    "DOCK_ATTEMPTS",
    "LEAVE_DOCK",
    "REFLEX_PRIORITY",
    "WalkReport",
    "bumper_reflex",
    "move",
    "random_walk",
    "suspending_reflex",
]

_log = logging.getLogger("pyrobots_aio.sim.random_walk")

REFLEX_PRIORITY = 10
"""The bumper reflex outranks every ordinary motion (priority 0)."""
BACK_OFF = 0.15
"""Metres the reflex backs off after a bump."""
DOCK_ATTEMPTS = 5
"""Docking attempts before the walk gives up (each interrupted one detours first)."""
LEAVE_DOCK = 0.5
"""Metres driven straight out after undocking, before the random moves."""
DETOUR = 0.4
"""Metres driven on, the way the reflex left the robot facing, before docking again."""
REFLEX_ROUNDS = 3
"""Back-off-and-turn rounds a reflex makes at most while the bumper stays pressed."""


@dataclass(frozen=True, slots=True)
class WalkReport:
    """What a random walk did.

    Attributes:
        moves: Turn-and-drive moves attempted.
        bumps: Bumper presses the reflex handled.
        interrupted: Moves the reflex cancelled (none with ``on_bump="suspend"``).
        docked: Whether the robot ended on its dock.
        sim_time: Simulated seconds the walk took.
    """

    moves: int
    bumps: int
    interrupted: int
    docked: bool
    sim_time: float


@action
@lock(WHEELS, priority=REFLEX_PRIORITY, preempt=True)
async def bumper_reflex(robot: DriveBase) -> None:
    """Back off, then turn away from the side that was hit (both sides: turn round).

    On the dock it only turns: the dock is behind (backing into it stalls the wheels).
    A back-off that stalls (the dock or a wall behind) ends where it stands, and
    the reflex turns there. It cancels the motion it preempts.
    """
    await _back_off_and_turn(robot)


@action
@lock(WHEELS, priority=REFLEX_PRIORITY, preempt="suspend")
async def suspending_reflex(robot: DriveBase) -> None:
    """The `bumper_reflex` that suspends the motion it preempts instead of cancelling it.

    The motion freezes (its wheels parked), and goes on where it stood once
    this reflex has released the wheels.
    """
    await _back_off_and_turn(robot)


async def _back_off_and_turn(robot: DriveBase) -> None:
    """Back off and turn; again while the bumper is still pressed (up to `REFLEX_ROUNDS`).

    A press that comes while the reflex runs starts no second reflex (the
    monitor drops it): if the reflex did not look again, the walk would drive
    on into what it touched (found by exploring the walk, issue 27).
    """
    for _ in range(REFLEX_ROUNDS):
        await _one_round(robot)
        if not (robot.state.bumper_left or robot.state.bumper_right):
            return


async def _one_round(robot: DriveBase) -> None:
    left, right = robot.state.bumper_left, robot.state.bumper_right
    turn = -0.9 if left and not right else 0.9 if right and not left else 0.75 * math.pi
    if robot.state.docked:
        _log.info("bump on the dock (left=%s right=%s): turning %.2f rad", left, right, turn)
    else:
        _log.info("bump (left=%s right=%s): backing off and turning %.2f rad", left, right, turn)
        try:
            await robot.drive_distance(-BACK_OFF)
        except StallError as stall:
            _log.info("backing off stalled, turning where it stands: %s", stall)
    await robot.rotate_angle(turn)


@action
async def move(robot: DriveBase, angle: float, distance: float) -> bool:
    """One random-walk move: turn by ``angle``, then drive ``distance``.

    Returns False if the bumper reflex preempted it (an outcome, not a failure).
    """
    try:
        await robot.rotate_angle(angle)
        await robot.drive_distance(distance)
    except ActionInterrupted as stop:
        _log.info("move interrupted: %s", stop.reason)
        return False
    return True


async def random_walk(
    robot: DriveBase,
    *,
    moves: int = 10,
    duration: float | None = None,
    seed: int = 0,
    on_bump: Literal["cancel", "suspend"] = "cancel",
) -> WalkReport:
    """Undock, drive out, make random moves, dock; a bumper reflex handles collisions.

    Args:
        robot: A running robot base (it starts docked, as a Create 3 does).
        moves: Random turn-and-drive moves to make.
        duration: If given, keep making moves until this many simulated seconds
            have passed since the start (at least ``moves`` moves are made first).
        seed: Seeds the choice of moves.
        on_bump: What the reflex does to the motion it preempts: ``"cancel"``
            it (`bumper_reflex`; the move is counted as interrupted) or
            ``"suspend"`` it (`suspending_reflex`; the motion resumes after
            the reflex, with its remaining distance).

    Raises:
        ValueError: ``on_bump`` is neither ``"cancel"`` nor ``"suspend"``.
    """
    reflexes = {"cancel": bumper_reflex, "suspend": suspending_reflex}
    if on_bump not in reflexes:
        msg = f"on_bump must be 'cancel' or 'suspend', got {on_bump!r}"
        raise ValueError(msg)
    rng = random.Random(seed)
    start = robot.time()
    reflex = robot.whenever("bumper", becomes=True).do(reflexes[on_bump])
    done = interrupted = 0
    try:
        await _leave_dock(robot)
        while done < moves or (duration is not None and robot.time() - start < duration):
            angle, distance = rng.uniform(-math.pi, math.pi), rng.uniform(0.3, 1.0)
            if not await move(robot, angle, distance):
                interrupted += 1
            done += 1
        docked = await _dock(robot)
        reflex.stop_monitoring()
        await _reflexes_done(robot)  # a bump at the very end: let the reflex back off
    finally:
        await reflex.close()
    docked = docked and bool(robot.state.docked)
    return WalkReport(done, reflex.firings, interrupted, docked, robot.time() - start)


async def _leave_dock(robot: DriveBase) -> None:
    """Undock and drive out `LEAVE_DOCK`; a bump on the way is the reflex's, and the walk goes on.

    (The Create 3 script's walk died here: a bump during the undock or the
    first drive ended it, and the reflex with it.)
    """
    try:
        await robot.undock()
        await robot.drive_distance(LEAVE_DOCK)
    except ActionInterrupted as stop:
        _log.info("leaving the dock interrupted: %s", stop.reason)


async def _dock(robot: DriveBase) -> bool:
    """Dock; after a bump, go round the obstacle (bug-style) instead of retrying straight.

    A bump just as the robot docked makes the reflex back it off the dock: it docks again.
    """
    for attempt in range(1, DOCK_ATTEMPTS + 1):
        try:
            await robot.dock()
        except ActionInterrupted:
            _log.info("docking attempt %d interrupted by a bump; detouring", attempt)
            await _detour(robot)
            continue
        await _reflexes_done(robot)
        if robot.state.docked:
            return True
    return bool(robot.state.docked)


async def _detour(robot: DriveBase) -> None:
    """Drive on `DETOUR` metres once the reflex has turned away (it may bump again)."""
    try:
        await robot.drive_distance(DETOUR)  # queued behind the reflex, which holds the wheels
    except ActionInterrupted:
        _log.info("detour interrupted by a bump")


async def _reflexes_done(robot: DriveBase) -> None:
    """Wait until every bumper reflex started so far is done (at once if there is none)."""
    names = {bumper_reflex.name, suspending_reflex.name}
    for handle in robot.handles():
        if handle.name in names:
            await handle.wait_done()
