"""The ROS 2 snippets of the README and the ROS 2 guide run, as a user would run them: beside a
sim-node process."""

from __future__ import annotations

import asyncio
import re
import sys
from pathlib import Path

import pytest
from ros2_support import DEADLINE, require_rclpy

from snippets_support import GUIDES, README, blocks

require_rclpy()
pytest.importorskip(
    "mujoco", reason="sim-node needs the sim extra: pip install 'pyrobots-aio[sim]'"
)

from test_sim_node import sim_node, stop  # noqa: E402

DOCUMENTS = (README, GUIDES / "guides" / "ros2.md")


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


@pytest.mark.asyncio
async def test_the_ros2_snippet_drives_a_sim_node(tmp_path: Path) -> None:
    import signal

    script = tmp_path / "drive.py"
    script.write_text(SNIPPETS[0])
    async with asyncio.timeout(DEADLINE), sim_node("--namespace", "/robot1") as node:
        user = await asyncio.create_subprocess_exec(
            sys.executable,
            str(script),
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, err = await user.communicate()
        assert user.returncode == 0, err.decode()
        assert re.fullmatch(r"drove 0\.1\d m\n", out.decode())
        assert (await stop(node, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
@pytest.mark.parametrize("profile", ["standard", "create3"])
async def test_the_ros2_robot_snippets_walk_a_sim_node(tmp_path: Path, profile: str) -> None:
    import signal

    if profile == "create3":
        pytest.importorskip("irobot_create_msgs", reason="pyrobots-aio ros2 interfaces build")
    script = tmp_path / "walk.py"
    script.write_text((ROBOT_SNIPPETS if profile == "standard" else CREATE3_SNIPPETS)[0])
    async with (
        asyncio.timeout(DEADLINE * 2),
        sim_node("--namespace", "/robot1", "--rate", "4", "--profile", profile) as node,
    ):
        user = await asyncio.create_subprocess_exec(
            sys.executable,
            str(script),
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, err = await user.communicate()
        assert user.returncode == 0, err.decode()
        assert out.decode() == "3 moves, docked: True\n"
        assert (await stop(node, signal.SIGINT))[0] == 0


@pytest.mark.asyncio
async def test_the_served_action_snippet_turns_a_sim_node(tmp_path: Path) -> None:
    import signal

    pytest.importorskip("irobot_create_msgs", reason="pyrobots-aio ros2 interfaces build")
    script = tmp_path / "serve.py"
    script.write_text(SERVE_SNIPPETS[0])
    async with asyncio.timeout(DEADLINE), sim_node("--namespace", "/robot1") as node:
        user = await asyncio.create_subprocess_exec(
            sys.executable,
            str(script),
            stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.PIPE,
        )
        out, err = await user.communicate()
        assert user.returncode == 0, err.decode()
        assert re.fullmatch(r"turned to 1\.0\d rad\n", out.decode())
        assert (await stop(node, signal.SIGINT))[0] == 0
