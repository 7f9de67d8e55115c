"""The ROS 2 snippets of the README and the ROS 2 guide run, as a user would run them: beside a
sim-node process."""

from __future__ import annotations

import asyncio
import re
import sys
from pathlib import Path

import pytest
from ros2_support import DEADLINE, require_interfaces, require_rclpy, require_sim

from snippets_support import GUIDES, README, RUN_ELSEWHERE, all_blocks, blocks

require_rclpy()
require_sim()

from test_sim_node import sim_node, stop  # noqa: E402

GUIDE = GUIDES / "guides" / "ros2.md"
DOCUMENTS = (README, GUIDE)


def _snippets(marker: str) -> list[str]:
    """The documents' blocks with ``marker``, each code once (the README and the guide share)."""
    return sorted({code for document in DOCUMENTS for code in blocks(document, "python", marker)})


SNIPPETS = _snippets("ros2")
ROBOT_SNIPPETS = _snippets("ros2-robot")
SERVE_SNIPPETS = _snippets("ros2-serve")
CREATE3_SNIPPETS = _snippets("ros2-create3")


def test_the_readme_has_a_ros2_snippet() -> None:
    assert len(SNIPPETS) == 1
    assert len(ROBOT_SNIPPETS) == 1
    assert len(SERVE_SNIPPETS) == 1
    assert len(CREATE3_SNIPPETS) == 1
    for document in (d for d in DOCUMENTS if blocks(d, "python", "ros2")):
        text = document.read_text()
        assert "pyrobots-aio sim-node --namespace /robot1 --profile create3 --rate 4" in text
        assert "pyrobots-aio sim-node --namespace /robot1 --rate 4" in text
        assert "pyrobots-aio sim-node --namespace /robot1" in text


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
    out = await _run_beside(
        _script(tmp_path / "drive.py", SNIPPETS[0]), DEADLINE, "--namespace", "/robot1"
    )
    assert re.fullmatch(r"drove 0\.1\d m\n", out)


@pytest.mark.asyncio
@pytest.mark.parametrize("profile", ["standard", "create3"])
async def test_the_ros2_robot_snippets_walk_a_sim_node(tmp_path: Path, profile: str) -> None:
    if profile == "create3":
        require_interfaces("irobot_create_msgs")
    code = (ROBOT_SNIPPETS if profile == "standard" else CREATE3_SNIPPETS)[0]
    node = ("--namespace", "/robot1", "--rate", "4", "--profile", profile)
    out = await _run_beside(_script(tmp_path / "walk.py", code), DEADLINE * 2, *node)
    assert out == "3 moves, docked: True\n"


@pytest.mark.asyncio
async def test_the_served_action_snippet_turns_a_sim_node(tmp_path: Path) -> None:
    require_interfaces("irobot_create_msgs")
    node = ("--namespace", "/robot1")
    out = await _run_beside(_script(tmp_path / "serve.py", SERVE_SNIPPETS[0]), DEADLINE, *node)
    assert re.fullmatch(r"turned to 1\.0\d rad\n", out)
