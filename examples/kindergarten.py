"""Kindergarten: the pyRobots paper's stress test, on the simulated robot.

A companion robot spends a session with children. In the background it blinks
and keeps looking at the child; it wanders about slowly. Five monitors react to
the session: the pacifier taken away (cry) or given back (thank), the toy
squeezed (its scale reading rises: giggle), the bumper pressed (back off), and
someone very close in front (say hello). A scripted session of 68 simulated
minutes with randomised events drives it, in lockstep virtual time. A safety
cap of 20 running actions is enforced, as in the paper; it reports actions and
events per minute and how often the cap was hit (the paper: 70 actions/min on
average, peaks at 200/min, the cap hit 31 times).

Run: ``python examples/kindergarten.py [--minutes M] [--seed N]``
"""

from __future__ import annotations

import argparse
import asyncio
import math
import random
from collections import Counter
from dataclasses import dataclass

from pyrobots_aio import (
    EventKind,
    ExecEvent,
    Robot,
    TooManyActions,
    action,
)
from pyrobots_aio.sim import SimRobot, run
from pyrobots_aio.sim.random_walk import bumper_reflex, move

SAFETY_CAP = 20


class PerMinute:
    """An instrument counting spawned actions and monitor firings per simulated minute."""

    def __init__(self) -> None:
        self.actions: Counter[int] = Counter()
        self.events: Counter[int] = Counter()

    def on_event(self, event: ExecEvent) -> None:
        if event.kind is EventKind.ACTION_SPAWNED:
            self.actions[int(event.time // 60)] += 1
        elif event.kind is EventKind.MONITOR_FIRED:
            self.events[int(event.time // 60)] += 1


@dataclass
class Session:
    """What happened during the session."""

    minutes: int
    actions_per_minute: float
    peak_actions_per_minute: int
    events_per_minute: float
    cap_hits: int
    reactions: Counter[str]


class Kid(SimRobot):
    """The companion robot: expressions are short actions on its (pretend) face."""

    def __init__(self, seed: int) -> None:
        self.meter = PerMinute()
        super().__init__(seed=seed, max_actions=SAFETY_CAP, instruments=[self.meter])
        self.cap_hits = 0
        self.reactions: Counter[str] = Counter()

    def react(self, expression: str) -> None:
        """Start an expression, unless the safety cap is reached (then count the hit)."""
        try:
            express(self, expression)
        except TooManyActions:
            self.cap_hits += 1
        else:
            self.reactions[expression] += 1


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
    await robot.undock()
    while True:
        await move(robot, rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 0.8))  # may be cut short
        await robot.sleep(rng.uniform(5.0, 20.0))


async def session_script(robot: Robot, minutes: int, rng: random.Random) -> None:
    """The children: pacifier, toy and a wandering child position, at random times."""
    end = robot.time() + minutes * 60
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


async def main(minutes: int = 68, seed: int = 0) -> Session:
    rng = random.Random(seed)
    async with Kid(seed) as robot:
        robot.state.update(pacifier=True, scale=0.0, child_x=1.0, child_y=0.0)
        robot.whenever("pacifier", becomes=False).do(robot.react, "cry")
        robot.whenever("pacifier", becomes=True).do(robot.react, "thank")
        robot.whenever("scale", increase=0.5).do(robot.react, "giggle")
        robot.whenever("bumper", becomes=True).do(bumper_reflex)
        robot.whenever("ir_front_center_left", below=0.15, max_firing_freq=0.2).do(
            robot.react, "hello"
        )
        background = [blink(robot, rng), look_at_child(robot), wander(robot, rng)]
        await session_script(robot, minutes, rng)
        for handle in background:
            handle.cancel("the session is over")
        await asyncio.gather(*(h.wait_done() for h in background))
        per_minute = [robot.meter.actions[m] for m in range(minutes)]
        return Session(
            minutes=minutes,
            actions_per_minute=sum(per_minute) / minutes,
            peak_actions_per_minute=max(per_minute),
            events_per_minute=sum(robot.meter.events.values()) / minutes,
            cap_hits=robot.cap_hits,
            reactions=robot.reactions,
        )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--minutes", type=int, default=68)
    parser.add_argument("--seed", type=int, default=0)
    options = parser.parse_args()
    result = run(main, options.minutes, options.seed)
    print(f"{result.minutes} simulated minutes")
    peak = result.peak_actions_per_minute
    print(f"actions per minute: {result.actions_per_minute:.0f} (peak {peak})")
    print(f"events per minute:  {result.events_per_minute:.1f}")
    print(f"safety cap of {SAFETY_CAP} actions hit {result.cap_hits} times")
    print(f"reactions: {dict(result.reactions)}")
