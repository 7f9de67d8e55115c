"""``examples/create3_walk.py``, a plain rclpy Create 3 program, unchanged against a sim-node."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import pytest
from ros2_support import DEADLINE, require_interfaces, require_rclpy, require_sim, run_script

require_rclpy()
require_sim()
require_interfaces("irobot_create_msgs")

from test_sim_node import sim_node  # noqa: E402

EXAMPLE = Path(__file__).parent.parent.parent / "examples" / "create3_walk.py"
STALL = ("--stall-timeout", "20")
"""The program, not the base, ends a drive that bumps: at the default 1.5 simulated seconds
(0.4 s of the wall clock at --rate 4), a loaded machine may hold the program's hazard
callback up until the base has given up on its stalled drive (then aborted, not cancelled)."""


@pytest.mark.asyncio
async def test_the_create3_program_undocks_walks_is_cancelled_by_a_bump_and_docks() -> None:
    async with (
        asyncio.timeout(DEADLINE * 2),
        sim_node("--namespace", "/walker", "--profile", "create3", "--rate", "4", *STALL),
    ):
        code, out, err = await run_script(EXAMPLE, "--external", "--namespace", "/walker")
    told = f"stdout:\n{out}\nstderr (end):\n{err[-3000:]}"
    assert code == 0, told
    summary = re.fullmatch(r"6 moves, (\d+) drives cancelled by bumps, docked\n", out)
    assert summary is not None, told
    assert int(summary[1]) >= 1, told  # seed 0 drives into a wall
    assert "bump: cancelling the drive" in err
