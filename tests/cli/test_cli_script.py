"""The installed ``pyrobots-aio`` script, run with the README's own commands, word for word."""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from pyrobots_aio.recording import format_summary, load, summarize

README = Path(__file__).parents[2] / "README.md"


def _script() -> str:
    """The console script installed beside the interpreter running the tests."""
    beside = Path(sys.executable).with_name("pyrobots-aio")
    found = str(beside) if beside.is_file() else shutil.which("pyrobots-aio")
    assert found is not None, f"no pyrobots-aio script beside {sys.executable}: pip install -e ."
    return found


def _readme_commands() -> list[list[str]]:
    """Every ``pyrobots-aio demo ...`` and ``pyrobots-aio replay ...`` command of the README."""
    text = README.read_text(encoding="utf-8")
    return [shlex.split(line) for line in re.findall(r"pyrobots-aio (?:demo|replay) [^`\n]+", text)]


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [_script(), *args], cwd=cwd, capture_output=True, text=True, timeout=300, check=False
    )


def test_the_readme_demo_and_replay_run_as_written(tmp_path: Path) -> None:
    demo, replay = _readme_commands()
    assert demo[:3] == ["pyrobots-aio", "demo", "random-walk"]
    assert replay[:2] == ["pyrobots-aio", "replay"]
    record = demo[demo.index("--record") + 1]
    assert replay[2] == record  # the README replays what its demo recorded

    done = _run(demo[1:], tmp_path)
    assert done.returncode == 0, done.stderr
    recording = load(tmp_path / record)
    assert recording.complete
    summary = format_summary(summarize(recording))
    assert f"\n{summary}\n" in done.stdout
    assert done.stdout.endswith(
        f"recorded to {record}; see its timeline with: {' '.join(replay)}\n"
    )

    shown = _run(replay[1:], tmp_path)
    assert (shown.returncode, shown.stderr) == (0, "")
    page = replay[replay.index("--timeline") + 1]
    assert shown.stdout == f"{summary}\n\ntimeline written to {page}\n"
    html = (tmp_path / page).read_text(encoding="utf-8")
    assert html.count('<rect class="action ') == summarize(recording).actions
