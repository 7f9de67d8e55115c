"""``pyrobots-aio replay`` and the command's exit codes, run as a user would (a subprocess)."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio.cli import main
from pyrobots_aio.recording import JsonlRecorder, McapRecorder
from pyrobots_aio.sim import SimRobot, run

if TYPE_CHECKING:
    from pathlib import Path

SUMMARY = [
    "Robot: 4.000 s recorded, 19 events, closed cleanly",
    "  actions            4: 3 succeeded, 0 failed, 1 cancelled, 0 skipped, 0 not done",
    "  actions per minute 60.0 mean; by minute: 4",
    "  events per minute  0.0 mean (monitor firings); by minute: 0",
    "  peak concurrency   2 actions at 0.000 s",
    "",
    "  action  count  ok  failed  cancelled  skipped  min s  median s  max s",
    "  greet       1   1       0          0        0  3.000     3.000  3.000",
    "  wave        3   2       0          1        0  1.000     1.000  2.000",
    "  (durations: from action.started to done, waits for resources included)",
    "",
    "  resource  held s     use  acquired  waits  max wait s  preempted",
    "  arm        4.000  100.0%         3      0       0.000          0",
    "",
    "  cancellations (1)",
    "        4.000 s  wave#4 cancelled: bored",
]


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "pyrobots_aio.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def test_replay_prints_the_summary_and_writes_the_timeline(recording: Path, tmp_path: Path) -> None:
    page = tmp_path / "out.html"
    done = _cli("replay", str(recording), "--timeline", str(page))
    assert (done.returncode, done.stderr) == (0, "")
    assert done.stdout.splitlines() == [*SUMMARY, "", f"timeline written to {page}"]
    html = page.read_text()
    assert html.count('<rect class="action ') == 4
    assert html.count('<rect class="hold"') == 3


def test_replay_of_a_truncated_recording_summarises_the_good_part(
    recording: Path, tmp_path: Path
) -> None:
    lines = recording.read_text().splitlines(keepends=True)
    cut = tmp_path / "cut.jsonl"
    cut.write_text("".join(lines[:8]) + lines[8][:30])
    page = tmp_path / "cut.html"
    done = _cli("replay", str(cut), "--timeline", str(page))
    assert done.returncode == 1
    assert done.stdout.splitlines()[:2] == [
        "Robot: 1.000 s recorded, 7 events, NOT closed (incomplete)",
        "  actions            2: 1 succeeded, 0 failed, 0 cancelled, 0 skipped, 1 not done",
    ]
    assert done.stderr.splitlines() == [
        f"pyrobots-aio: error: {cut}:9: truncated line: it ends before its JSON object does "
        "(was the recorder closed?) (the summary covers the 7 events before it)",
    ]
    assert "truncated line" in page.read_text()


def test_replay_of_a_missing_file_fails_cleanly(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere.jsonl"
    done = _cli("replay", str(missing))
    assert (done.returncode, done.stdout) == (1, "")
    assert done.stderr == f"pyrobots-aio: error: cannot read {missing}: No such file or directory\n"


def test_replay_of_something_else_fails_cleanly(tmp_path: Path) -> None:
    other = tmp_path / "notes.txt"
    other.write_text("hello\n")
    done = _cli("replay", str(other))
    assert (done.returncode, done.stdout) == (1, "")
    assert done.stderr == (
        f"pyrobots-aio: error: {other}:1: not valid JSON: Expecting value at column 1\n"
    )


def test_replay_of_an_mcap_file_gives_the_same_summary_and_page(tmp_path: Path) -> None:
    run(_record_both, tmp_path / "walk.mcap", tmp_path / "walk.jsonl")
    assert (tmp_path / "walk.mcap").read_bytes().startswith(b"\x89MCAP0\r\n")
    mcap = _cli("replay", str(tmp_path / "walk.mcap"), "--timeline", str(tmp_path / "m.html"))
    jsonl = _cli("replay", str(tmp_path / "walk.jsonl"), "--timeline", str(tmp_path / "j.html"))
    assert (mcap.returncode, mcap.stderr, jsonl.returncode, jsonl.stderr) == (0, "", 0, "")
    assert mcap.stdout.splitlines()[:-1] == jsonl.stdout.splitlines()[:-1]
    assert mcap.stdout.startswith("SimRobot, seed 5: ")
    assert "rotate_angle#3 cancelled: bored" in mcap.stdout
    pages = [(tmp_path / name).read_text() for name in ("m.html", "j.html")]
    assert pages[0].replace("walk.mcap", "walk.jsonl") == pages[1]


async def _record_both(mcap: Path, jsonl: Path) -> None:
    robot = SimRobot(seed=5)
    with McapRecorder(mcap).attach(robot), JsonlRecorder(jsonl).attach(robot):
        async with robot:
            await robot.undock()
            turn = robot.rotate_angle(3.0)
            await robot.sleep(1.0)
            turn.cancel("bored")
            await turn.wait_done()


def test_replay_refuses_to_write_the_page_over_the_recording(recording: Path) -> None:
    before = recording.read_bytes()
    link = recording.with_name("link.html")
    link.symlink_to(recording)
    for target in (str(recording), f"{recording.parent}/./{recording.name}", str(link)):
        done = _cli("replay", str(recording), "--timeline", target)
        assert (done.returncode, done.stdout) == (2, "")
        assert done.stderr == (
            f"pyrobots-aio: error: --timeline {target} names the recording itself; writing the "
            "page there would destroy it: choose another file, e.g. run.html\n"
        )
    assert recording.read_bytes() == before


def test_replay_refuses_a_page_that_is_not_html_or_cannot_be_written(
    recording: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Before: --timeline out.txt wrote HTML into out.txt without a word.
    where = recording.parent
    refusals = {
        "out.txt": f"--timeline {where / 'out.txt'}: the page is HTML, its name should end in "
        f".html, e.g. {where / 'out.html'}",
        "nodir/run.html": f"--timeline {where / 'nodir/run.html'}: the directory "
        f"{where / 'nodir'} does not exist: create it first, or choose another",
        "pages.html": f"--timeline {where / 'pages.html'} is a directory: name a file, e.g. "
        f"{where / 'pages.html/run.html'}",
    }
    (where / "pages.html").mkdir()
    for name, problem in refusals.items():
        assert main(["replay", str(recording), "--timeline", str(where / name)]) == 2
        assert capsys.readouterr() == ("", f"pyrobots-aio: error: {problem}\n")
    assert sorted(p.name for p in where.iterdir()) == [recording.name, "pages.html"]


def test_replay_prints_no_terminal_escape_from_a_recording(tmp_path: Path) -> None:
    evil = "\x1b]0;owned\x07\x1b[2J\x1b[31m"
    path = tmp_path / "evil.jsonl"
    lines = [
        {"format": "pyrobots_aio.recording", "version": 1, "t0": 0.0, "robot": evil},
        {"t": 0.0, "action": 1, "kind": "action.spawned", "name": evil, "data": {}},
        {"t": 1.0, "action": 1, "kind": "action.finished", "name": evil, "data": {"error": evil}},
        {"t": 1.0, "kind": evil},
    ]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    done = _cli("replay", str(path))
    assert done.returncode == 1
    assert "\x1b" not in done.stdout + done.stderr
    assert "\x07" not in done.stdout + done.stderr
    assert "\\x1b]0;owned\\x07" in done.stdout
    assert "unknown event kind" in done.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((), "error: the following arguments are required: COMMAND"),
        (("demo",), "error: the following arguments are required: DEMO"),
        (("replay",), "error: the following arguments are required: PATH"),
        (
            ("demo", "random-walk", "--duration", "-1"),
            "error: argument --duration: expected a positive number of seconds, got '-1'",
        ),
        (
            ("demo", "random-walk", "--seed", "one"),
            "error: argument --seed: expected a non-negative integer, got 'one'",
        ),
        (  # was a 30-line traceback from the simulator
            ("demo", "random-walk", "--seed", "-1"),
            "error: argument --seed: expected a non-negative integer, got '-1'",
        ),
        (("fly",), "error: argument COMMAND: invalid choice: 'fly'"),
    ],
)
def test_usage_errors_exit_with_2(args: tuple[str, ...], message: str) -> None:
    done = _cli(*args)
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr.startswith("usage: pyrobots-aio")
    assert message in done.stderr


def test_main_returns_the_exit_code(capsys: pytest.CaptureFixture[str], recording: Path) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out == "pyrobots-aio 0.1.0\n"
    assert main(["replay", str(recording)]) == 0
    assert capsys.readouterr().out.splitlines() == SUMMARY
    assert main(["replay"]) == 2
