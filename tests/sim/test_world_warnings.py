"""MuJoCo warnings go to the ``pyrobots_aio.sim`` logger, not to a file in the current directory."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from pyrobots_aio.sim import SimWorld

if TYPE_CHECKING:
    import pytest

UNSTABLE = "MuJoCo: Nan, Inf or huge value in QACC at DOF 0. The simulation is unstable."


def _blow_up() -> None:
    """Make MuJoCo warn: a 5 s physics step is far too long for a turning robot."""
    world = SimWorld(physics_dt=5.0)
    world.set_command(0.3, 2.0)
    world.advance(50.0)


def test_a_mujoco_warning_is_logged_and_no_log_file_appears(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    capfd: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    _blow_up()
    assert list(tmp_path.iterdir()) == []  # MuJoCo's own handler wrote MUJOCO_LOG.TXT here
    warnings = [
        (r.name, r.levelno, r.getMessage()) for r in caplog.records if r.levelno >= logging.WARNING
    ]
    assert len(warnings) == 1
    name, level, message = warnings[0]
    assert (name, level) == ("pyrobots_aio.sim", logging.WARNING)
    assert message.startswith(UNSTABLE)
    assert capfd.readouterr() == ("", "")  # nor printed by MuJoCo itself


def test_a_programs_own_mujoco_warning_handler_is_left_in_place(tmp_path: Path) -> None:
    program = (
        "import mujoco\n"
        "from test_world_warnings import _blow_up\n"
        "seen = []\n"
        "mujoco.set_mju_user_warning(seen.append)\n"
        "_blow_up()\n"
        "print(len(seen), seen[0][:20])\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", program],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(Path(__file__).parent)},
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "1 Nan, Inf or huge val\n", "")
    assert list(tmp_path.iterdir()) == []
