"""Kindergarten: the pyRobots paper's stress test, on the simulated robot.

A companion robot spends a session with children. In the background it blinks
and keeps looking at the child; it wanders about slowly. Five monitors react to
the session: the pacifier taken away (cry) or given back (thank), the toy
squeezed (its scale reading rises: giggle), the bumper pressed (back off), and
someone very close in front (say hello). A scripted session of 68 simulated
minutes with randomised events drives it, in lockstep virtual time. A safety
cap of 20 running actions is enforced, as in the paper; it reports actions and
events per minute and how often the cap was hit (the paper: 70 actions/min on
average, peaks at 200/min, the cap hit 31 times). Whatever the cap refuses (an
expression, a move, the bumper reflex) is counted and skipped, and the robot
carries on.

Run: ``python examples/kindergarten.py [--minutes M] [--seed N] [--cap N]``
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import math
import random
from collections import Counter
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pyrobots_aio import (
    ActionInterrupted,
    EventKind,
    ExecEvent,
    TooManyActions,
    action,
)
from pyrobots_aio.cli import install_console_handler
from pyrobots_aio.sim import SimRobot, run
from pyrobots_aio.sim.random_walk import bumper_reflex, move

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from pyrobots_aio import Instrument

SAFETY_CAP = 20


class PerMinute:
    """An instrument counting spawned actions and monitor firings per minute since ``start``."""

    def __init__(self) -> None:
        self.start = 0.0
        self.actions: Counter[int] = Counter()
        self.events: Counter[int] = Counter()

    def on_event(self, event: ExecEvent) -> None:
        minute = int((event.time - self.start) // 60)
        if event.kind is EventKind.ACTION_SPAWNED:
            self.actions[minute] += 1
        elif event.kind is EventKind.MONITOR_FIRED:
            self.events[minute] += 1


@dataclass
class Session:
    """What happened during the session.

    ``reactions`` counts what the robot started in reaction (expressions by
    name, ``back_off`` for the bumper reflex); ``refused`` what the safety cap
    refused (the same names, and ``move`` for the wandering); ``cap_hits`` is
    the total refused.
    """

    minutes: int
    actions_per_minute: float
    peak_actions_per_minute: int
    events_per_minute: float
    peak_events_per_minute: int
    safety_cap: int
    cap_hits: int
    reactions: Counter[str]
    refused: Counter[str]


class Kid(SimRobot):
    """The companion robot: expressions are short actions on its (pretend) face.

    The safety cap refuses any action started while ``max_actions`` run; the
    robot counts each refusal in ``refused`` (by what was refused) and carries
    on without it.
    """

    def __init__(
        self, seed: int, max_actions: int = SAFETY_CAP, instruments: Iterable[Instrument] = ()
    ) -> None:
        self.meter = PerMinute()
        self.safety_cap = max_actions
        super().__init__(seed=seed, max_actions=max_actions, instruments=[self.meter, *instruments])
        self.reactions: Counter[str] = Counter()
        self.refused: Counter[str] = Counter()

    def react(self, expression: str) -> None:
        """Start an expression, unless the safety cap is reached (then count the hit)."""
        self.attempt(expression, express, expression)

    def attempt(self, what: str, start: Callable[..., object], *args: object) -> None:
        """Start the action ``start(self, *args)``; count it as ``what``, started or refused."""
        try:
            start(self, *args)
        except TooManyActions:
            self.refused[what] += 1
        else:
            self.reactions[what] += 1


@action
async def express(robot: Kid, expression: str) -> None:
    """Show an expression on the face for a moment."""
    await robot.sleep({"blink": 0.15, "cry": 3.0, "giggle": 1.0}.get(expression, 0.6))


@action
async def blink(robot: Kid, rng: random.Random) -> None:
    while True:
        await robot.sleep(rng.uniform(2.0, 6.0))
        robot.react("blink")


@action
async def look_at_child(robot: Kid) -> None:
    """Turn the (pretend) head to the child every second."""
    while True:
        await robot.sleep(1.0)
        pan, tilt = robot.poses.pantilt((robot.state.child_x, robot.state.child_y, 0.4))
        robot.state.update(head_pan=pan, head_tilt=tilt)
        robot.react("look")


@action
async def wander(robot: Kid, rng: random.Random) -> None:
    """Slow random moves; one the safety cap refuses (it or a step of it) is skipped.

    The bumper reflex may cut any step short, the undock too: the wander goes
    on with its next move (a bump while undocking once ended it for good).
    """
    while True:
        angle, distance = rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 0.8)
        try:
            if robot.state.docked:
                await robot.undock()
            await move(robot, angle, distance)  # may be cut short by the bumper reflex
        except TooManyActions:
            robot.refused["move"] += 1
        except ActionInterrupted:
            pass  # the reflex took the wheels while undocking; it has turned the robot away
        await robot.sleep(rng.uniform(5.0, 20.0))


@action
async def back_off(robot: Kid) -> None:
    """The bumper reflex; if the safety cap refuses a step of it, count the hit and stop."""
    try:
        await bumper_reflex(robot)
    except TooManyActions:
        robot.refused["back_off"] += 1


async def session_script(
    robot: Kid,
    minutes: int,
    rng: random.Random,
    progress: Callable[[int, int, int], object] | None = None,
) -> None:
    """The children: pacifier, toy and a wandering child position, at random times.

    At the end of each simulated minute it calls ``progress(minute, actions, events)``
    (the actions started and events fired in that minute), if given.
    """
    start = robot.time()
    end, reported = start + minutes * 60, 0
    next_pacifier, next_toy = rng.uniform(30, 120), rng.uniform(10, 40)
    while robot.time() < end:
        await robot.sleep(1.0)
        now = robot.time()
        robot.state.update(child_x=rng.uniform(-1.5, 1.5), child_y=rng.uniform(-1.5, 1.5))
        if now >= next_pacifier:
            robot.state.pacifier = not robot.state.pacifier
            next_pacifier = now + rng.uniform(30, 180)
        if now >= next_toy:
            for _ in range(rng.randint(1, 4)):  # a burst of squeezes; the scale counts them up
                robot.state.scale = robot.state.scale + rng.uniform(0.6, 1.5)
                await robot.sleep(0.2)
            next_toy = now + rng.uniform(10, 60)
        if progress is not None and robot.time() >= start + 60 * (reported + 1):
            reported += 1
            minute = reported - 1  # just completed
            progress(reported, robot.meter.actions[minute], robot.meter.events[minute])


async def session(
    robot: Kid,
    minutes: int = 68,
    seed: int = 0,
    progress: Callable[[int, int, int], object] | None = None,
) -> Session:
    """Run the session on ``robot`` (running); see `session_script` for ``progress``."""
    rng = random.Random(seed)
    # one stream each: how long the robot's moves take does not change the children's script
    blink_rng, walk_rng, script_rng = (random.Random(rng.getrandbits(64)) for _ in range(3))
    robot.meter.start = robot.time()
    robot.state.update(pacifier=True, scale=0.0, child_x=1.0, child_y=0.0)
    robot.whenever("pacifier", becomes=False).do(robot.react, "cry")
    robot.whenever("pacifier", becomes=True).do(robot.react, "thank")
    robot.whenever("scale", increase=0.5).do(robot.react, "giggle")
    robot.whenever("bumper", becomes=True).do(robot.attempt, "back_off", back_off)
    robot.whenever("ir_front_center_left", below=0.15, max_firing_freq=0.2).do(robot.react, "hello")
    background = [blink(robot, blink_rng), look_at_child(robot), wander(robot, walk_rng)]
    await session_script(robot, minutes, script_rng, progress)
    for handle in background:
        handle.cancel("the session is over")
    await asyncio.gather(*(h.wait_done() for h in background))
    actions = [robot.meter.actions[m] for m in range(minutes)]
    events = [robot.meter.events[m] for m in range(minutes)]
    return Session(
        minutes=minutes,
        actions_per_minute=sum(actions) / minutes,
        peak_actions_per_minute=max(actions),
        events_per_minute=sum(events) / minutes,
        peak_events_per_minute=max(events),
        safety_cap=robot.safety_cap,
        cap_hits=robot.refused.total(),
        reactions=robot.reactions,
        refused=robot.refused,
    )


async def main(
    minutes: int = 68,
    seed: int = 0,
    max_actions: int = SAFETY_CAP,
    instruments: Iterable[Instrument] = (),
    progress: Callable[[int, int, int], object] | None = None,
) -> Session:
    """Run the session; ``instruments`` also receive the executive's events."""
    async with Kid(seed, max_actions, instruments) as robot:
        return await session(robot, minutes, seed, progress)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--minutes", type=int, default=68, help="simulated minutes of the session (default: 68)"
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seeds the session's random events and the simulator (default: 0)",
    )
    parser.add_argument("--cap", type=int, default=SAFETY_CAP, help="the safety cap (max_actions)")
    options = parser.parse_args()
    install_console_handler(logging.WARNING)  # INFO would log each of the session's bumps

    def show(minute: int, actions: int, events: int) -> None:
        print(
            f"minute {minute:2}/{options.minutes}: {actions:3} actions, {events:2} events",
            flush=True,
        )

    result = run(main, options.minutes, options.seed, options.cap, (), show)
    print(f"{result.minutes} simulated minutes")
    peak = result.peak_actions_per_minute
    print(f"actions per minute: {result.actions_per_minute:.0f} (peak {peak})")
    print(
        f"events per minute:  {result.events_per_minute:.1f} (peak {result.peak_events_per_minute})"
    )
    print(f"safety cap of {result.safety_cap} actions hit {result.cap_hits} times")
    print(f"started: {dict(result.reactions)}")
    print(f"refused: {dict(result.refused)}")
