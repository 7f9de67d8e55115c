"""``pyrobots-aio demo random-walk`` end to end: a subprocess, a terminal, and the recording."""

from __future__ import annotations

import os
import pty
import re
import subprocess
import sys
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import EventKind
from pyrobots_aio.cli import main
from pyrobots_aio.recording import format_summary, load, summarize

if TYPE_CHECKING:
    from pathlib import Path

    from pyrobots_aio.recording import Recording

COMMAND = [sys.executable, "-m", "pyrobots_aio.cli", "demo", "random-walk"]


def _events(recording: Recording) -> list[tuple[str, float, int | None, str | None, object]]:
    """The run's events, but for the loop watchdog's: a stall of the machine, not of the run."""
    return [
        (e.kind.value, e.time, e.action, e.name, dict(e.data))
        for e in recording.events
        if e.kind is not EventKind.LOOP_BLOCKED
    ]


def test_the_demo_runs_records_and_summarises(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "walk.jsonl"
    done = subprocess.run(
        [*COMMAND, "--duration", "60", "--record", str(path), "--seed", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    out = done.stdout.splitlines()
    # not a terminal: a line of counters every 10 simulated seconds while it runs, no more
    progress = out[: out.index(next(line for line in out if line.startswith("random walk: ")))]
    assert progress[0] == "   10.000  progress 6 actions, 0 cancelled, 0 failed, 0 monitor firings"
    assert [line[:19] for line in progress] == [
        f"{10.0 * n:9.3f}  progress" for n in range(1, len(progress) + 1)
    ]
    assert len(progress) == 8  # 82.82 s
    assert not any("  start    " in line for line in out)
    assert not any("\x1b[" in line for line in out)

    recording = load(path)
    summary = summarize(recording)
    assert recording.complete
    assert (recording.header.robot, recording.header.seed) == ("SimRobot", 1)
    assert recording.header.metadata == {"demo": "random-walk"}
    assert summary.duration >= 60
    assert summary.actions > 20
    assert {s.name for s in summary.per_action} >= {"undock", "move", "rotate_angle", "dock"}
    assert [r.name for r in summary.resources] == ["wheels"]
    sensors = {"bumper", "docked", "v", "w", "battery", "ir_front_left", "cliff_front_left"}
    assert sensors <= set(recording.samples)  # every sensor key, and the pose
    ticks = round(summary.duration * 50) + 1
    assert len(recording.samples["v"]) > ticks / 2  # at the control rate while moving
    assert len(recording.poses) > ticks / 2
    for cancel in summary.cancellations:  # every bump is explained
        assert cancel.by_name is not None
        assert cancel.by_name.startswith("bumper_reflex#")
        assert cancel.reason is not None
        assert cancel.reason.startswith("preempted by bumper_reflex#")
    reports = [line for line in out if line.startswith("random walk: ")]
    assert len(reports) == 1
    assert f"{summary.monitor_firings.get('bumper becomes=True', 0)} bumps" in reports[0]
    assert " (lockstep, x" in reports[0]
    assert reports[0].endswith(" real time)")
    assert format_summary(summary) in done.stdout
    assert done.stdout.endswith(
        f"recorded to {path}; see its timeline with: pyrobots-aio replay {path} "
        f"--timeline {tmp_path / 'walk.html'}\n"
    )

    # the same seed, in-process this time: the very same run
    again = tmp_path / "again.jsonl"
    assert (
        main(
            ["-q", "demo", "random-walk", "--duration", "60", "--record", str(again), "--seed", "1"]
        )
        == 0
    )
    rerun = load(again)
    assert format_summary(summarize(rerun)) in capsys.readouterr().out
    # The same actions, resources and monitor firings at the same times, the same samples
    # and poses. (A loop-watchdog event in either recording is the machine stalling.)
    assert _events(rerun) == _events(recording)
    assert rerun.samples == recording.samples
    assert rerun.poses == recording.poses


def test_realtime_follows_the_wall_clock(tmp_path: Path) -> None:
    # About 21 s: undocking, driving out and docking take 20.84 simulated seconds.
    path = tmp_path / "walk.jsonl"
    done = subprocess.run(
        [*COMMAND, "--realtime", "--duration", "0.5", "--record", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    reports = [line for line in done.stdout.splitlines() if line.startswith("random walk: ")]
    assert len(reports) == 1
    found = re.search(
        r"; (\d+\.\d\d) s simulated in (\d+\.\d\d) s \(realtime, x(\d\.\d\d) real time\)$",
        reports[0],
    )
    assert found is not None, reports[0]
    simulated, wall, ratio = (float(group) for group in found.groups())
    # Loop time is the wall clock: the run cannot get ahead of it (lockstep runs x50 and more).
    assert simulated <= wall
    assert ratio <= 1.0
    recording = load(path)
    assert recording.complete
    assert recording.duration + 0.005 >= simulated  # the walk is recorded whole (2 decimals)
    assert format_summary(summarize(recording)) in done.stdout


def test_without_record_the_summary_comes_from_memory(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-q", "demo", "random-walk", "--duration", "5", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert "SimRobot, seed 2: " in out
    assert "closed cleanly" in out
    assert "recorded to" not in out


def test_verbose_prints_a_line_per_action_instead_of_progress(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["-q", "demo", "random-walk", "--duration", "5", "--seed", "2", "-v"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:3] == [
        "    0.000  start    undock#1",
        "    0.000  start    drive_distance#2 under undock#1",
        "    2.380  succeeded drive_distance#2",
    ]
    assert not any(" progress " in line for line in out)
    # the command's -v (debug logs) asks for them too
    assert main(["-v", "demo", "random-walk", "--duration", "5", "--seed", "2"]) == 0
    assert "    0.000  start    undock#1" in capsys.readouterr().out.splitlines()


def test_by_default_progress_lines_tick_in_simulated_time(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["-q", "demo", "random-walk", "--duration", "5", "--seed", "2"]) == 0
    out = capsys.readouterr().out.splitlines()
    report = next(i for i, line in enumerate(out) if line.startswith("random walk: "))
    simulated = float(out[report].split("; ")[1].split(" s simulated")[0])
    assert [line.split("  progress ")[0] for line in out[:report]] == [
        f"{10.0 * n:9.3f}" for n in range(1, int(simulated // 10) + 1)
    ]
    assert all(" actions, " in line and " cancelled, " in line for line in out[:report])


def _on_a_terminal(args: list[str]) -> tuple[int, str]:
    leader, follower = pty.openpty()
    env = {**os.environ, "COLUMNS": "100", "NO_COLOR": ""}
    with subprocess.Popen(args, stdin=follower, stdout=follower, stderr=follower, env=env) as child:
        os.close(follower)
        output = b""
        while True:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the child closed the terminal
                break
            if not chunk:
                break
            output += chunk
        code = child.wait(timeout=300)
    os.close(leader)
    return code, output.decode()


def test_on_a_terminal_the_status_is_redrawn_in_place() -> None:
    code, output = _on_a_terminal([*COMMAND, "--duration", "30", "--seed", "1"])
    assert code == 0, output
    assert "\x1b[J" in output  # the live block is erased before each redraw
    assert "random walk " in output
    assert "  running undock#1 running holds wheels at _base.py:" in output
    assert "  state   bumper=False  docked=" in output
    assert "\x1b[32mINFO   \x1b[0m sim.random_walk  bumper_reflex#" in output  # coloured log lines
    assert "start    undock#1" not in output  # on a terminal, routine starts are not listed
    assert "SimRobot, seed 1: " in output
