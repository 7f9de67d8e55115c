"""``demo random-walk --record PATH.jsonl|PATH.mcap`` and ``--serve``, run as a user would."""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import struct
import subprocess
import sys
from typing import TYPE_CHECKING, Any

import pytest
import websockets

from pyrobots_aio.cli import main
from pyrobots_aio.recording import load, summarize
from pyrobots_aio.telemetry import ARENA
from signal_support import HANG_GUARD, wait_delivered

if TYPE_CHECKING:
    from collections.abc import Iterable
    from pathlib import Path

COMMAND = [sys.executable, "-m", "pyrobots_aio.cli", "demo", "random-walk"]


def _demo(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*COMMAND, *args], capture_output=True, text=True, timeout=300, check=False
    )


@pytest.mark.parametrize("name", ["walk.txt", "walk", "walk.json", "walk.mcap.gz"])
def test_an_unknown_extension_is_refused(tmp_path: Path, name: str) -> None:
    done = _demo("--record", str(tmp_path / name))
    assert (done.returncode, done.stdout) == (2, "")
    assert (
        f"error: argument --record: cannot tell the format of '{tmp_path / name}' from its "
        "extension: use .jsonl or .mcap (JSON Lines or MCAP)"
    ) in done.stderr
    assert list(tmp_path.iterdir()) == []


def test_the_extension_picks_the_format_and_both_replay_alike(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    runs = {}
    for name in ("walk.mcap", "walk.jsonl"):
        done = _demo("--duration", "20", "--seed", "4", "--record", str(tmp_path / name))
        assert done.returncode == 0, done.stderr
        runs[name] = load(tmp_path / name)
        notes = [line for line in done.stdout.splitlines() if str(tmp_path / name) in line]
        hint = (
            f"recorded to {tmp_path / name}; see its timeline with: pyrobots-aio replay "
            f"{tmp_path / name} --timeline {tmp_path / 'walk.html'}"
        )
        if name == "walk.mcap":  # the quiet seconds of closing and reading back are announced
            assert notes == [
                f"closing {tmp_path / name}: compressing the last chunk and writing the MCAP "
                "index and summary",
                f"reading {tmp_path / name} back for its summary",
                hint,
            ]
        else:
            assert notes == [hint]
    mcap = (tmp_path / "walk.mcap").read_bytes()
    assert mcap.startswith(b"\x89MCAP0\r\n")
    with (tmp_path / "walk.mcap").open("rb") as file:
        summary = make_reader(file).get_summary()
    assert summary is not None
    topics = {c.topic for c in summary.channels.values()}
    assert {"/pyrobots/pose", "/tf", "/pyrobots/log", "/pyrobots/state/v"} <= topics
    assert summarize(runs["walk.mcap"]) == summarize(runs["walk.jsonl"])  # the same seeded run
    assert runs["walk.mcap"].header.floor_plan == runs["walk.jsonl"].header.floor_plan


async def _watch(
    port: int, wanted: frozenset[str] = frozenset({"/pyrobots/pose", "/pyrobots/actions"})
) -> dict[str, list[dict[str, Any]]]:
    """Subscribe to the ``wanted`` topics; return what came once each did."""
    url = f"ws://127.0.0.1:{port}"
    protocol = websockets.Subprotocol("foxglove.sdk.v1")
    got: dict[str, list[dict[str, Any]]] = {}
    async with websockets.connect(url, subprotocols=[protocol]) as ws:
        topics: dict[int, str] = {}
        while not wanted <= set(got):
            frame = await ws.recv()
            if isinstance(frame, str):
                body = json.loads(frame)
                for channel in body.get("channels", []) if body["op"] == "advertise" else []:
                    if channel["topic"] in wanted:
                        ident = len(topics) + 1
                        topics[ident] = channel["topic"]
                        subscribe = [{"id": ident, "channelId": channel["id"]}]
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscribe}))
            else:
                _, ident, _ = struct.unpack_from("<BIQ", frame)
                got.setdefault(topics[ident], []).append(json.loads(frame[13:]))
    return got


def _port(lines: Iterable[str], pattern: str) -> int:
    """The port in the first line that matches ``pattern`` (its group 1)."""
    for line in lines:
        found = re.search(pattern, line)
        if found:
            return int(found.group(1))
    raise AssertionError(f"no line matched {pattern!r}")


def test_serve_streams_the_run_live(tmp_path: Path) -> None:
    with subprocess.Popen(
        [*COMMAND, "--realtime", "--serve", "0", "--duration", "30"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    ) as demo:
        try:
            assert demo.stderr is not None
            # the console log says where it serves
            port = _port(demo.stderr, r"live view on ws://127\.0\.0\.1:(\d+)")
            got = asyncio.run(asyncio.wait_for(_watch(port), 60))  # a hang guard
        finally:
            demo.send_signal(signal.SIGINT)
            demo.wait(timeout=60)
    assert {p["frame_id"] for p in got["/pyrobots/pose"]} == {"map"}
    first = got["/pyrobots/actions"][0]  # whatever the walk was doing when the client came
    assert str(first["kind"]).startswith("action.")
    assert first["name"] in {"undock", "drive_distance", "move", "rotate_angle"}


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_keep_serving_serves_after_the_walk_until_a_signal(signum: signal.Signals) -> None:
    # Before: the server stopped with the walk, and a client that came after found nothing.
    with subprocess.Popen(
        [*COMMAND, "--serve", "0", "--keep-serving", "--duration", "5"],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    ) as demo:
        try:
            assert demo.stdout is not None
            # after the summary, it says it serves on
            ready = r"^the walk is over; still serving the live view on ws://127\.0\.0\.1:(\d+): "
            port = _port(demo.stdout, ready + r"Ctrl-C stops$")
            got = asyncio.run(asyncio.wait_for(_watch(port, frozenset({ARENA})), 60))
            assert demo.poll() is None  # serving still
            demo.send_signal(signum)
            wait_delivered(demo, signum)
            assert demo.wait(timeout=HANG_GUARD) == 0
            rest = demo.stdout.read()
        finally:
            if demo.poll() is None:
                demo.kill()
    assert rest == f"stopped serving ws://127.0.0.1:{port}\n"
    (scene,) = got[ARENA]  # the walk is over, and a new client still sees the arena
    assert {e["id"] for e in scene["entities"]} >= {"dock", "wall_north", "pillar"}


def _refused(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    """Run the demo in-process with ``args``; it must fail at once: exit 2, one line, no output."""
    assert main(["demo", "random-walk", *args]) == 2
    out, err = capsys.readouterr()
    assert out == ""  # no progress line: the simulation never started
    assert err.count("\n") == 1
    return err


def test_keep_serving_without_serve_is_refused_before_the_run(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert _refused(capsys, "--keep-serving") == (
        "pyrobots-aio: error: --keep-serving keeps the live view of --serve up: "
        "add --serve (or --serve PORT)\n"
    )


def test_a_record_path_in_a_missing_directory_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Before: "[Errno 2] No such file or directory: ..." after 2.4 s of simulation.
    path = tmp_path / "nodir" / "x.jsonl"
    assert _refused(capsys, "--record", str(path)) == (
        f"pyrobots-aio: error: --record {path}: the directory {tmp_path / 'nodir'} does not "
        "exist: create it first, or choose another\n"
    )
    assert list(tmp_path.iterdir()) == []


def test_a_record_path_that_is_a_directory_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Before: "[Errno 21] Is a directory: ..." after 2.4 s of simulation.
    path = tmp_path / "somedir.jsonl"
    path.mkdir()
    assert _refused(capsys, "--record", str(path)) == (
        f"pyrobots-aio: error: --record {path} is a directory: name a file, "
        f"e.g. {path / 'walk.jsonl'}\n"
    )
    assert list(path.iterdir()) == []


def test_a_record_path_in_a_directory_one_may_not_write_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The tests may run as root, whom permissions do not stop: the check is what is tested.
    path = tmp_path / "x.mcap"
    monkeypatch.setattr(os, "access", lambda *_args, **_kwargs: False)
    assert _refused(capsys, "--record", str(path)) == (
        f"pyrobots-aio: error: --record {path}: the directory {tmp_path} may not be written "
        "(permission denied): choose another\n"
    )
    path.touch()
    assert _refused(capsys, "--record", str(path)) == (
        f"pyrobots-aio: error: --record {path}: the file may not be overwritten "
        "(permission denied)\n"
    )
