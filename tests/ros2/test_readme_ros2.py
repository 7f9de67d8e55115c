"""The ROS 2 snippets of the README and the ROS 2 guide run, as a user would run them: beside a
sim-node process."""

from __future__ import annotations

import asyncio
import re
import sys
from pathlib import Path

import pytest
from ros2_support import DEADLINE, PEER_SILENCE, require_interfaces, require_rclpy, require_sim

from snippets_support import GUIDES, README, RUN_ELSEWHERE, all_blocks, blocks

require_rclpy()
require_sim()

from test_sim_node import sim_node, stop  # noqa: E402

from pyrobots_aio.motion import ANGLE_TOLERANCE  # noqa: E402

GUIDE = GUIDES / "guides" / "ros2.md"
DOCUMENTS = (README, GUIDE)


def _snippets(marker: str) -> list[str]:
    """The documents' blocks with ``marker``, each code once (the README and the guide share)."""
    return sorted({code for document in DOCUMENTS for code in blocks(document, "python", marker)})


# The sim-nodes the guide names beside the snippets: the robot's (at 4x, each command held
# PEER_SILENCE of the wall clock, as its odom_timeout waits for odometry), the Create 3's, and
# the real-time one the teleop and serving snippets drive.
ROBOT_NODE = ("--namespace", "/robot1", "--rate", "4", "--cmd-timeout", "40")
CREATE3_NODE = (
    "--namespace",
    "/robot1",
    "--profile",
    "create3",
    "--rate",
    "4",
    "--cmd-timeout",
    "40",
)
NODE = ("--namespace", "/robot1")
SNIPPETS = _snippets("ros2")
ROBOT_SNIPPETS = _snippets("ros2-robot")
SERVE_SNIPPETS = _snippets("ros2-serve")
CREATE3_SNIPPETS = _snippets("ros2-create3")


def test_the_readme_has_a_ros2_snippet() -> None:
    assert len(SNIPPETS) == 1
    assert len(ROBOT_SNIPPETS) == 1
    assert len(SERVE_SNIPPETS) == 1
    assert len(CREATE3_SNIPPETS) == 1
    assert float(ROBOT_NODE[-1]) == PEER_SILENCE * 4
    for document in (d for d in DOCUMENTS if blocks(d, "python", "ros2")):
        text = document.read_text()
        for node in (ROBOT_NODE, CREATE3_NODE, NODE):
            assert f"`pyrobots-aio sim-node {' '.join(node)}" in text
        for code in (*ROBOT_SNIPPETS, *CREATE3_SNIPPETS):
            assert f"odom_timeout={PEER_SILENCE * 4}" in code


def test_the_guide_counts_its_snippets_and_says_nothing_served_is_missing() -> None:
    numbers = ("no", "one", "two", "three", "four", "five", "six")
    ran_here = [b for b in all_blocks(GUIDE) if b.marker in RUN_ELSEWHERE]
    text = GUIDE.read_text()
    assert f"The {numbers[len(ran_here)]} snippets of this page" in text
    assert "## The executive served to ROS 2" in text
    assert "not built yet" not in text


def _script(path: Path, code: str) -> Path:
    """``code`` written to ``path``, as a user's script."""
    path.write_text(code)
    return path


async def _run_beside(script: Path, deadline: float, *node_args: str) -> str:
    """Run ``script`` beside a sim-node; its stdout, once both ended cleanly."""
    import signal

    async with asyncio.timeout(deadline), sim_node(*node_args) as node:
        user = await asyncio.create_subprocess_exec(
            sys.executable,
            str(script),
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, err = await user.communicate()
        assert user.returncode == 0, err.decode()
        assert (await stop(node, signal.SIGINT))[0] == 0
    return out.decode()


@pytest.mark.asyncio
async def test_the_ros2_snippet_drives_a_sim_node(tmp_path: Path) -> None:
    out = await _run_beside(_script(tmp_path / "drive.py", SNIPPETS[0]), DEADLINE, *NODE)
    drove = re.fullmatch(r"drove (0\.\d\d) m\n", out)
    assert drove is not None, out
    # At least the 0.1 m it drives to; past it by what its last commands still drove, however
    # late a loaded machine lets it see the odometry: each command holds 0.5 s (--cmd-timeout)
    # at 0.2 m/s, and a tick (0.004 m) and the wheels' slowing down come on top.
    assert 0.10 <= float(drove[1]) <= 0.1 + 0.2 * 0.5 + 0.01


@pytest.mark.asyncio
@pytest.mark.parametrize("profile", ["standard", "create3"])
async def test_the_ros2_robot_snippets_walk_a_sim_node(tmp_path: Path, profile: str) -> None:
    if profile == "create3":
        require_interfaces("irobot_create_msgs")
    code, node = (
        (ROBOT_SNIPPETS, ROBOT_NODE) if profile == "standard" else (CREATE3_SNIPPETS, CREATE3_NODE)
    )
    out = await _run_beside(_script(tmp_path / "walk.py", code[0]), DEADLINE * 2, *node)
    assert out == "3 moves, docked: True\n"


@pytest.mark.asyncio
async def test_the_served_action_snippet_turns_a_sim_node(tmp_path: Path) -> None:
    require_interfaces("irobot_create_msgs")
    out = await _run_beside(_script(tmp_path / "serve.py", SERVE_SNIPPETS[0]), DEADLINE, *NODE)
    turned = re.fullmatch(r"turned to (\d\.\d\d) rad\n", out)
    assert turned is not None, out
    # The 1 rad asked, within the turn's tolerance; past it by what its last commands still
    # turned, however late a loaded machine lets it see the odometry (as the drive above).
    assert 1.0 - ANGLE_TOLERANCE - 0.005 <= float(turned[1]) <= 1.0 + 1.0 * 0.5 + 0.02
