"""``pyrobots-aio demo random-walk``: the simulated random walk, shown as it runs.

Lockstep virtual time by default (`pyrobots_aio.sim.run`: as fast as the CPU
allows), or ``--realtime`` on an ordinary loop. While it runs: a live block on
a terminal, one line per notable event otherwise, and with ``--serve`` a live
view in Foxglove. At the end: the walk's report and the summary of its
recording (the file of ``--record``, JSON Lines or MCAP by its extension, else
an in-memory recording). Every state key and the pose are recorded at the
control rate.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import time
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    MemoryRecorder,
    format_summary,
    load,
    summarize,
)

from ._live import EventLines, LiveStatus, Tally

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine
    from typing import Any

    from pyrobots_aio import Robot
    from pyrobots_aio.recording import Recorder, Recording
    from pyrobots_aio.sim.random_walk import WalkReport

    from ._console import ConsoleHandler

RECORDERS = {".jsonl": JsonlRecorder, ".mcap": McapRecorder}
"""The recorder each ``--record`` extension picks."""
DEFAULT_PORT = 8765
"""The port of ``--serve`` without a number (Foxglove's default)."""
DEFAULT_MOVES = 10
"""Moves made when no ``--duration`` is given."""


def positive_seconds(text: str) -> float:
    """Argparse type: a positive, finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        msg = f"expected a positive number of seconds, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def recording_path(text: str) -> str:
    """Argparse type: a recording file whose extension names a known format."""
    if Path(text).suffix.lower() not in RECORDERS:
        msg = (
            f"cannot tell the format of {text!r} from its extension: "
            f"use {' or '.join(RECORDERS)} (JSON Lines or MCAP)"
        )
        raise argparse.ArgumentTypeError(msg)
    return text


def port_number(text: str) -> int:
    """Argparse type: a TCP port number (0: any free port)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= 65535:
        msg = f"expected a TCP port number from 0 to 65535, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def add_parser(demos: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``random-walk`` to the ``demo`` sub-commands."""
    walk = demos.add_parser(
        "random-walk",
        help="the simulated robot's random walk with a bumper reflex",
        description="Undock, wander with random turns and drives, dock; a bumper reflex "
        "preempts the current move and the walk carries on.",
    )
    walk.add_argument(
        "--duration",
        type=positive_seconds,
        metavar="SECONDS",
        help="make random moves until this many simulated seconds have passed since the "
        "start; the move under way and docking come on top, so the run lasts longer "
        f"(default: {DEFAULT_MOVES} moves)",
    )
    walk.add_argument(
        "--realtime",
        action="store_true",
        help="follow the wall clock (default: lockstep, as fast as possible); undocking, "
        "driving out and docking alone take about 20 s",
    )
    walk.add_argument(
        "--record",
        metavar="PATH",
        type=recording_path,
        help="record the run (every state key and the pose at the control rate) to this file: "
        "PATH.jsonl for JSON Lines, PATH.mcap for MCAP (Foxglove; the mcap extra)",
    )
    walk.add_argument(
        "--serve",
        metavar="PORT",
        nargs="?",
        const=DEFAULT_PORT,
        type=port_number,
        help="stream the run live over Foxglove's WebSocket protocol on 127.0.0.1:PORT "
        f"(default {DEFAULT_PORT}; the live extra); use it with --realtime to watch it",
    )
    walk.add_argument(
        "--seed", type=int, default=0, help="seeds the sensors and the moves (default: 0)"
    )
    walk.set_defaults(command=run_random_walk)


class _Show:
    """How the run is shown: a live block on a terminal, event lines otherwise."""

    def __init__(self, out: TextIO, handler: ConsoleHandler) -> None:
        self.tally = Tally()
        self.handler = handler
        self.wall_start = time.perf_counter()  # for the speed-up shown; never used for timing
        self.start = 0.0
        if out.isatty():
            self.live: LiveStatus | None = LiveStatus(out, self._headline)
            self.events = EventLines(self.live.line, 0.0, verbose=False)
            self._saved = handler.stream
            handler.stream = self.live  # log lines scroll above the block
        else:
            self.live = None
            self.events = EventLines(
                lambda line: print(line, file=out, flush=True), 0.0, verbose=True
            )
        self._robot: Robot | None = None

    def attach(self, robot: Robot) -> None:
        self._robot = robot
        self.start = self.events.start = asyncio.get_running_loop().time()
        robot.instruments.add(self.tally)
        robot.instruments.add(self.events)

    def showing(self, robot: Robot) -> contextlib.AbstractAsyncContextManager[None]:
        return self.live.showing(robot) if self.live is not None else contextlib.nullcontext()

    def _headline(self) -> str:
        robot, t = self._robot, self.tally
        sim = robot.time() - self.start if robot is not None and robot.is_running else 0.0
        wall = time.perf_counter() - self.wall_start
        speed = f"x{sim / wall:.0f}" if wall > 0 else ""
        return (
            f"random walk {sim:7.2f} s {speed:>5}  actions {t.actions}  "
            f"cancelled {t.cancelled}  failed {t.failed}  events {t.firings}"
        )

    def close(self) -> None:
        if self.live is not None:
            self.handler.stream = self._saved


def _recorder(options: argparse.Namespace) -> Recorder:
    metadata = {"demo": "random-walk"}
    if not options.record:
        return MemoryRecorder(metadata=metadata)
    if Path(options.record).suffix.lower() == ".mcap":
        return McapRecorder(options.record, metadata=metadata, logs=True)
    return JsonlRecorder(options.record, metadata=metadata)


def _walk(
    options: argparse.Namespace, recorder: Recorder, show: _Show
) -> Callable[[], Coroutine[Any, Any, WalkReport]]:
    from pyrobots_aio.sim import SimRobot
    from pyrobots_aio.sim.random_walk import random_walk

    moves = 0 if options.duration is not None else DEFAULT_MOVES

    async def main() -> WalkReport:
        robot = SimRobot(seed=options.seed, realtime=options.realtime, serve=options.serve)
        show.attach(robot)
        with recorder.attach(robot):
            async with robot, show.showing(robot):
                return await random_walk(
                    robot, moves=moves, duration=options.duration, seed=options.seed
                )

    return main


def _report(report: WalkReport, wall: float, *, realtime: bool) -> str:
    ratio = report.sim_time / wall if wall > 0 else 0.0
    speed = f"x{ratio:.0f}" if ratio >= 10 else f"x{ratio:.2f}"
    mode = "realtime" if realtime else "lockstep"
    docked = "docked" if report.docked else "NOT docked"
    return (
        f"random walk: {report.moves} moves, {report.bumps} bumps, {report.interrupted} moves "
        f"interrupted, {docked}; {report.sim_time:.2f} s simulated in {wall:.2f} s "
        f"({mode}, {speed} real time)"
    )


def run_random_walk(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run the demo; return the exit code."""
    from pyrobots_aio.sim import run  # first: without the sim extra, fail before writing files

    recorder = _recorder(options)
    show = _Show(out, options.log_handler)
    try:
        main = _walk(options, recorder, show)
        report = asyncio.run(main()) if options.realtime else run(main)
    finally:
        recorder.close()
        show.close()
    wall = time.perf_counter() - show.wall_start
    print(_report(report, wall, realtime=options.realtime), file=out)
    recording: Recording
    recording = (
        recorder.recording() if isinstance(recorder, MemoryRecorder) else load(options.record)
    )
    print("", format_summary(summarize(recording)), sep="\n", file=out)
    if options.record:
        replay = f"pyrobots-aio replay {options.record} --timeline run.html"
        print(f"\nrecorded to {options.record}; see its timeline with: {replay}", file=out)
    return 0
