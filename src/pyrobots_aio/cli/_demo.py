"""``pyrobots-aio demo random-walk``: the simulated random walk, shown as it runs.

Lockstep virtual time by default (`pyrobots_aio.sim.run`: as fast as the CPU
allows), or ``--realtime`` on an ordinary loop. While it runs: a live block on
a terminal, otherwise a line of counters every ten simulated seconds (with
``-v``, a line per action started and finished and per notable event instead),
and with ``--serve`` a live view in Foxglove. At the end: the walk's report and the summary of its
recording (the file of ``--record``, JSON Lines or MCAP by its extension, else
an in-memory recording). Every state key and the pose are recorded at the
control rate. With ``--keep-serving``, the live view then stays up (Foxglove
stays connected, with what it received, and shows the arena to a client that
comes later) until Ctrl-C or SIGTERM, which end the demo with status 0.

Ctrl-C and SIGTERM stop the walk in order (`stop_on_signals`): the first
shuts the robot down (its cleanup bounded, the wheels stopped, the recording
closed), a second cuts the cleanup short. A closed output pipe (``| head``)
stops the walk the same way.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import errno
import signal
import time
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from pyrobots_aio.loops import run_scaled
from pyrobots_aio.recording import (
    JsonlRecorder,
    McapRecorder,
    MemoryRecorder,
    format_summary,
    load,
    summarize,
)
from pyrobots_aio.robot import SignalStop, stop_on_signals
from pyrobots_aio.telemetry import LiveView

from ._live import EventLines, LiveStatus, Progress, Tally
from ._paths import unwritable

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine, Iterator
    from typing import Any

    from pyrobots_aio import Robot
    from pyrobots_aio.recording import Recorder, Recording, Sink
    from pyrobots_aio.sim.random_walk import WalkReport

    from ._console import ConsoleHandler

RECORDERS = {".jsonl": JsonlRecorder, ".mcap": McapRecorder}
"""The recorder each ``--record`` extension picks."""
DEFAULT_PORT = 8765
"""The port of ``--serve`` without a number (Foxglove's default)."""
DEFAULT_MOVES = 10
"""Moves made when no ``--duration`` is given."""
PROGRESS = 10.0
"""Simulated seconds between progress lines (not on a terminal, without ``-v``)."""
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""What ends ``--keep-serving``."""


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


def _integer(text: str, low: int, high: int | None, expected: str) -> int:
    """``text`` as an integer from ``low`` to ``high`` (None: unbounded), or a usage error."""
    try:
        value = int(text)
    except ValueError:
        value = low - 1
    if value < low or (high is not None and value > high):
        msg = f"expected {expected}, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def port_number(text: str) -> int:
    """Argparse type: a TCP port number (0: any free port)."""
    return _integer(text, 0, 65535, "a TCP port number from 0 to 65535")


def seed(text: str) -> int:
    """Argparse type: a non-negative integer (what seeds the simulator and the moves)."""
    return _integer(text, 0, None, "a non-negative integer")


def count(text: str) -> int:
    """Argparse type: a positive integer."""
    return _integer(text, 1, None, "a positive integer")


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
        f"(default {DEFAULT_PORT}; the live extra); use it with --realtime to watch it, "
        "or with --keep-serving",
    )
    walk.add_argument(
        "--keep-serving",
        action="store_true",
        help="with --serve: after the walk, keep the live view up (Foxglove stays connected "
        "with what it received) until Ctrl-C",
    )
    walk.add_argument(
        "-v",
        "--verbose",
        dest="per_action",
        action="store_true",
        help="print a line per action started and finished and per notable event "
        f"(default: a line of counters every {PROGRESS:g} simulated seconds; on a terminal, "
        "a live block)",
    )
    walk.add_argument(
        "--seed", type=seed, default=0, help="seeds the sensors and the moves (default: 0)"
    )
    walk.set_defaults(command=run_random_walk)


class _Show:
    """How the run is shown: a live block on a terminal, event lines otherwise."""

    def __init__(self, out: TextIO, handler: ConsoleHandler, *, per_action: bool) -> None:
        self.tally = Tally()
        self.handler = handler
        self.wall_start = time.perf_counter()  # for the speed-up shown; never used for timing
        self.start = 0.0
        self._out = out
        self._saved = handler.stream, handler.start
        self.pipe_closed = False
        self.progress: Progress | None = None
        self.events: EventLines | None
        if out.isatty():
            self.live: LiveStatus | None = LiveStatus(out, self._headline)
            self.events = EventLines(self.live.line, 0.0, verbose=False)
            handler.stream = self.live  # log lines scroll above the block
        else:
            self.live = None
            self.events = EventLines(self.note, 0.0, verbose=True) if per_action else None
            if not per_action:
                self.progress = Progress(self.note, self.tally, PROGRESS)
        self._robot: Robot | None = None
        self._task: asyncio.Task[object] | None = None

    def attach(self, robot: Robot) -> None:
        self._robot = robot
        self._task = asyncio.current_task()
        # Every time shown counts from the robot's start: event lines, log lines, headline.
        self.start = asyncio.get_running_loop().time()
        self.handler.start = self.start
        robot.instruments.add(self.tally)
        if self.events is not None:
            self.events.start = self.start
            robot.instruments.add(self.events)

    def note(self, line: str) -> None:
        """Write one line (an event's, progress, the command's own) unless the pipe closed."""
        if self.pipe_closed:
            return
        try:
            print(line, file=self._out, flush=True)
        except BrokenPipeError:  # the reader went away (``| head``): stop the walk in order
            self.pipe_closed = True
            if self._task is not None:
                self._task.cancel("the output pipe was closed")

    def showing(self, robot: Robot) -> contextlib.AbstractAsyncContextManager[None]:
        if self.live is not None:
            return self.live.showing(robot)
        if self.progress is not None:
            return self.progress.showing(self.start)
        return contextlib.nullcontext()

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
        self.handler.stream, self.handler.start = self._saved


def _recorder(options: argparse.Namespace) -> Recorder[Sink]:
    metadata = {"demo": "random-walk"}
    if not options.record:
        return MemoryRecorder(metadata=metadata)
    if _is_mcap(options):
        return McapRecorder(options.record, metadata=metadata, logs=True)
    return JsonlRecorder(options.record, metadata=metadata)


def _is_mcap(options: argparse.Namespace) -> bool:
    return bool(options.record) and Path(options.record).suffix.lower() == ".mcap"


@contextlib.contextmanager
def _closing_note(options: argparse.Namespace, show: _Show) -> Iterator[None]:
    """Say what the quiet seconds of closing an MCAP recording are spent on, before them."""
    try:
        yield
    finally:
        if _is_mcap(options):
            show.note(
                f"closing {options.record}: compressing the last chunk and writing the MCAP "
                "index and summary"
            )


def _walk(
    options: argparse.Namespace,
    recorder: Recorder[Sink],
    show: _Show,
    stopping: SignalStop,
    live: LiveView | None,
) -> Callable[[], Coroutine[Any, Any, WalkReport]]:
    from pyrobots_aio.sim import SimRobot
    from pyrobots_aio.sim.random_walk import random_walk

    moves = 0 if options.duration is not None else DEFAULT_MOVES
    serve = options.serve if live is None else live  # a view of our own outlives the robot

    async def main() -> WalkReport:
        robot = SimRobot(seed=options.seed, realtime=options.realtime, serve=serve)
        with stopping, recorder.attach(robot), _closing_note(options, show):
            async with robot:
                show.attach(robot)  # times shown count from here, as the recording's do
                async with show.showing(robot):
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


async def _until_signal(ready: str, out: TextIO) -> None:
    """Print ``ready``, then wait for SIGINT or SIGTERM (``--keep-serving``'s normal end)."""
    loop = asyncio.get_running_loop()
    stopped = asyncio.Event()
    for signum in STOP_SIGNALS:  # before saying so: a signal from then on is handled
        loop.add_signal_handler(signum, stopped.set)
    try:
        print(ready, file=out, flush=True)
        await stopped.wait()
    finally:
        for signum in STOP_SIGNALS:
            loop.remove_signal_handler(signum)


def _keep_serving(live: LiveView, out: TextIO) -> None:
    """Serve on after the walk, until Ctrl-C or SIGTERM."""
    url = f"ws://{live.host}:{live.port}"
    run_scaled(
        _until_signal,
        f"\nthe walk is over; still serving the live view on {url}: Ctrl-C stops",
        out,
    )
    print(f"stopped serving {url}", file=out, flush=True)


def _problem(options: argparse.Namespace) -> str | None:
    """What is wrong with the options that argparse cannot tell, in words; None if nothing."""
    if options.keep_serving and options.serve is None:
        return "--keep-serving keeps the live view of --serve up: add --serve (or --serve PORT)"
    record = options.record
    return unwritable("--record", record, f"walk{Path(record).suffix}") if record else None


def run_random_walk(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run the demo; return the exit code."""
    problem = _problem(options)
    if problem is not None:  # before the simulation: a typo costs no run
        print(f"pyrobots-aio: error: {problem}", file=err)
        return 2
    from pyrobots_aio.sim import run  # first: without the sim extra, fail before writing files

    live = LiveView(options.serve) if options.keep_serving else None
    try:
        _run(options, out, run, live)
        if live is not None:
            _keep_serving(live, out)
    finally:
        if live is not None:
            live.stop()
    return 0


def _run(
    options: argparse.Namespace,
    out: TextIO,
    run: Callable[[Callable[[], Coroutine[Any, Any, WalkReport]]], WalkReport],
    live: LiveView | None,
) -> None:
    """Walk, then print the report and the recording's summary."""
    recorder = _recorder(options)
    show = _Show(out, options.log_handler, per_action=options.per_action or options.verbose)
    stopping = stop_on_signals()
    try:
        main = _walk(options, recorder, show, stopping, live)
        report = run_scaled(main) if options.realtime else run(main)
    except asyncio.CancelledError:
        if show.pipe_closed:
            raise BrokenPipeError(errno.EPIPE, "the output pipe was closed") from None
        raise
    except BaseException:
        if stopping.received:  # the process is on its way out: later signals change nothing
            for signum in stopping.handled:
                signal.signal(signum, signal.SIG_IGN)
        raise
    finally:
        recorder.close()
        show.close()
    wall = time.perf_counter() - show.wall_start
    print(_report(report, wall, realtime=options.realtime), file=out)
    if _is_mcap(options):
        print(f"reading {options.record} back for its summary", file=out, flush=True)
    recording: Recording
    recording = (
        recorder.recording() if isinstance(recorder, MemoryRecorder) else load(options.record)
    )
    print("", format_summary(summarize(recording)), sep="\n", file=out)
    if options.record:
        page = Path(options.record).with_suffix(".html")
        replay = f"pyrobots-aio replay {options.record} --timeline {page}"
        print(f"\nrecorded to {options.record}; see its timeline with: {replay}", file=out)
