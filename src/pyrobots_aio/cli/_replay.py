"""``pyrobots-aio replay PATH [--timeline OUT.html]``: summarise a recording, draw its page.

JSON Lines and MCAP recordings give the same summary and page. A corrupt or
truncated recording is still summarised up to the bad line; the error, naming
that line, follows the summary and the exit code is 1. The recording is
untrusted input: its strings (and the paths given) are printed with control
characters and lone surrogates escaped, and ``--timeline`` must end in
``.html`` and be writable, and may not name the recording itself (exit code 2,
before the recording is read). What is not a regular file (a FIFO, ``/dev/zero``) is
refused with one line and exit code 1, like a file that cannot be read.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TextIO

from pyrobots_aio import RecordingError
from pyrobots_aio.recording import (
    format_summary,
    load,
    render_timeline_html,
    shown,
    summarize,
)

from ._paths import unwritable


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``replay`` command."""
    replay = commands.add_parser(
        "replay",
        help="summarise a recording and draw its timeline",
        description="Print the summary of a recording, JSON Lines or MCAP (actions and events "
        "per minute, peak concurrency, durations per action, resource use, cancellations) and, "
        "with --timeline, write its page: the map of the arena with the robot's path, the "
        "timeline of actions and resources, and plots of the sensors, as one self-contained "
        "HTML file. An action's "
        "duration runs from its start (action.started) to its end, so it includes any wait "
        "for a resource.",
    )
    replay.add_argument(
        "path",
        metavar="PATH",
        help="a recording: JSON Lines or MCAP (pyrobots-aio demo random-walk --record "
        "PATH.jsonl or PATH.mcap; JsonlRecorder, McapRecorder)",
    )
    replay.add_argument(
        "--timeline", metavar="OUT.html", help="write the page (map, timeline, plots) here"
    )
    replay.set_defaults(command=run_replay)


def run_replay(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run ``replay``; return the exit code."""
    problem = _timeline_problem(options.path, options.timeline) if options.timeline else None
    if problem is not None:
        print(f"pyrobots-aio: error: {problem}", file=err)
        return 2
    try:
        recording = load(options.path, strict=False)
    except RecordingError as exc:
        print(f"pyrobots-aio: error: {shown(exc)}", file=err)
        return 1
    except OSError as exc:
        print(f"pyrobots-aio: error: cannot read {shown(options.path)}: {exc.strerror}", file=err)
        return 1
    print(format_summary(summarize(recording)), file=out)
    if options.timeline:
        try:
            Path(options.timeline).write_text(render_timeline_html(recording), encoding="utf-8")
        except OSError as exc:
            problem = f"cannot write {shown(options.timeline)}: {exc.strerror}"
            print(f"pyrobots-aio: error: {problem}", file=err)
            return 1
        print(f"\ntimeline written to {shown(options.timeline)}", file=out)
    if recording.error is not None:
        covered = f"the summary covers the {len(recording.events)} events before it"
        print(f"pyrobots-aio: error: {shown(recording.error)} ({covered})", file=err)
        return 1
    return 0


def _timeline_problem(recording: str, page: str) -> str | None:
    """What is wrong with ``--timeline page``, before the recording is read; None: nothing."""
    if _same_file(recording, page):
        return (
            f"--timeline {shown(page)} names the recording itself; writing the "
            "page there would destroy it: choose another file, e.g. run.html"
        )
    if Path(page).suffix.lower() not in {".html", ".htm"}:
        return (
            f"--timeline {shown(page)}: the page is HTML, its name should end in .html, "
            f"e.g. {shown(Path(page).with_suffix('.html'))}"
        )
    return unwritable("--timeline", page, "run.html")


def _same_file(recording: str, page: str) -> bool:
    """Whether ``page`` is the file ``recording`` (the same path, a link to it ...)."""
    try:
        return Path(recording).resolve() == Path(page).resolve() or (
            Path(page).exists() and Path(recording).samefile(page)
        )
    except OSError:
        return False
