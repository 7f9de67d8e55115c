"""``examples/random_walk_ros2.py`` runs as a user would run it: it starts its own sim-node."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import pytest
from ros2_support import DEADLINE, PEER_SILENCE, require_rclpy, require_sim, run_script

require_rclpy()
require_sim()

EXAMPLE = Path(__file__).parent.parent.parent / "examples" / "random_walk_ros2.py"


@pytest.mark.asyncio
async def test_the_example_walks_a_sim_node_over_ros2_bumps_and_docks() -> None:
    async with asyncio.timeout(DEADLINE * 2):
        # Either process may be held up PEER_SILENCE on a loaded machine (not the default 0.5 s)
        silence = ("--silence", str(PEER_SILENCE))
        code, out, err = await run_script(
            EXAMPLE, "--namespace", "/example", "--moves", "5", *silence
        )
    told = f"stdout:\n{out}\nstderr (end):\n{err[-3000:]}"
    assert code == 0, told
    lines = out.splitlines()
    assert re.fullmatch(
        r"sim-node /example/sim_node ready \(domain \d+, x4 real time\): .*", lines[0]
    )
    summary = re.fullmatch(
        r"5 moves, (\d+) bumps handled, (\d+) moves interrupted, docked, ([\d.]+) s simulated",
        lines[-1],
    )
    assert summary is not None, told
    assert float(summary[3]) > 20, told  # it drove out, made its moves and came back
    # Seed 0 runs into a wall: the reflex preempted a move, and the walk went on to its end.
    assert int(summary[1]) >= 1, told
    assert int(summary[2]) >= 1, told
    assert "ROS 2 node /example/pyrobots_aio up" in err
