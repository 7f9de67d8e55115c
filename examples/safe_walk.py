"""Safe walk: cancel a running action; its cleanup awaits another action.

The pyRobots listing, asyncio style: ``safe_walk`` starts ``walk``; cancelling
``safe_walk`` interrupts both, and the cleanup of ``safe_walk`` runs
``go_back_to_rest_pose`` to completion before the handle is done.

Run: ``python examples/safe_walk.py``
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING

from pyrobots_aio import ActionCancelled, ActionInterrupted, Outcome, Robot, action
from pyrobots_aio.cli import install_console_handler

if TYPE_CHECKING:
    from collections.abc import Iterable

    from pyrobots_aio import Instrument

log = logging.getLogger("safe_walk")


class Walker(Robot):
    """A robot with a pretend walking gait: it only logs what it would do."""

    @action
    async def walk(self, speed: float) -> None:
        log.info("walking at %.1f m/s", speed)
        await self.sleep(3600)

    @action
    async def go_back_to_rest_pose(self) -> str:
        log.info("going back to the rest pose")
        await self.sleep(0.2)
        return "rest"


@action
async def safe_walk(robot: Walker, speed: float = 0.2) -> None:
    try:
        await robot.walk(speed)
    except ActionCancelled:
        await robot.go_back_to_rest_pose()  # cleanup may await
        raise


async def main(instruments: Iterable[Instrument] = ()) -> Outcome:
    """Start ``safe_walk``, cancel it after a second; return its outcome.

    ``instruments`` receive the executive's events (a test checks the cleanup with them).
    """
    async with Walker(instruments=instruments) as robot:
        handle = safe_walk(robot, 0.3)
        await robot.sleep(1.0)
        print(robot.action_tree())
        handle.cancel("the user pressed stop")
        try:
            await handle
        except ActionInterrupted as interrupted:
            print(f"safe_walk ended: {interrupted}")
        return handle.outcome


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    outcome = asyncio.run(main())
    print(f"outcome: {outcome.name}")
