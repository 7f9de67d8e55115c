"""The README's ROS 2 snippets run, as a user would run them: beside a sim-node process."""

from __future__ import annotations

import asyncio
import re
import sys
from pathlib import Path

import pytest
from ros2_support import DEADLINE, require_rclpy

require_rclpy()
pytest.importorskip(
    "mujoco", reason="sim-node needs the sim extra: pip install 'pyrobots-aio[sim]'"
)

from test_sim_node import sim_node, stop  # noqa: E402

README = (Path(__file__).parent.parent.parent / "README.md").read_text()
SNIPPETS = re.findall(r"```python ros2\n(.*?)```", README, flags=re.DOTALL)
ROBOT_SNIPPETS = re.findall(r"```python ros2-robot\n(.*?)```", README, flags=re.DOTALL)
SERVE_SNIPPETS = re.findall(r"```python ros2-serve\n(.*?)```", README, flags=re.DOTALL)
CREATE3_SNIPPETS = re.findall(r"```python ros2-create3\n(.*?)```", README, flags=re.DOTALL)


def test_the_readme_has_a_ros2_snippet() -> None:
    assert len(SNIPPETS) == 1
    assert len(ROBOT_SNIPPETS) == 1
    assert len(SERVE_SNIPPETS) == 1
    assert len(CREATE3_SNIPPETS) == 1
    assert "pyrobots-aio sim-node --namespace /robot1 --profile create3 --rate 4" in README
    assert "pyrobots-aio sim-node --namespace /robot1 --rate 4" in README
    assert "pyrobots-aio sim-node --namespace /robot1" in README


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
