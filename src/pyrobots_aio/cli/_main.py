"""The ``pyrobots-aio`` command: argument parsing and exit codes.

Exit codes: 0 success, 1 runtime failure (a corrupt recording, an error of the
library or of the file system), 2 usage error (argparse, or an output path
that cannot be written, found before any work starts), 130 interrupted
(Ctrl-C), 141 the output pipe was closed (``| head``: quietly, as for any
command that SIGPIPE ends), 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import traceback
from typing import TextIO

from pyrobots_aio import PyRobotsError, __version__

from . import _demo, _interfaces, _replay, _sim_node
from ._console import install_console_handler

INTERRUPTED = 128 + signal.SIGINT
PIPE_CLOSED = 128 + signal.SIGPIPE
TERMINATED = 128 + signal.SIGTERM


def parser() -> argparse.ArgumentParser:
    """The command's argument parser."""
    top = argparse.ArgumentParser(
        prog="pyrobots-aio",
        description="pyrobots_aio: run the demo robot, replay recordings, serve the "
        "simulated robot over ROS 2.",
    )
    top.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    loud = top.add_mutually_exclusive_group()
    loud.add_argument("-v", "--verbose", action="store_true", help="log debug messages too")
    loud.add_argument("-q", "--quiet", action="store_true", help="log warnings and errors only")
    commands = top.add_subparsers(title="commands", metavar="COMMAND", required=True)
    _replay.add_parser(commands)
    demo = commands.add_parser(
        "demo",
        help="run a demo on the simulated robot",
        description="Run a demo on the simulated robot.",
    )
    demos = demo.add_subparsers(title="demos", metavar="DEMO", required=True)
    _demo.add_parser(demos)
    _sim_node.add_parser(commands)
    _interfaces.add_parser(commands)
    return top


def main(argv: list[str] | None = None) -> int:
    """Run ``pyrobots-aio`` with ``argv`` (default: ``sys.argv[1:]``); return the exit code.

    Examples:
        >>> from pyrobots_aio.cli import main
        >>> main(["replay", "run.jsonl", "--timeline", "run.html"])  # doctest: +SKIP
        0
    """
    try:
        options = parser().parse_args(argv)
    except SystemExit as exit_:  # --help, --version (0) and usage errors (2)
        return exit_.code if isinstance(exit_.code, int) else 2
    out, err = sys.stdout, sys.stderr
    level = logging.DEBUG if options.verbose else logging.WARNING if options.quiet else logging.INFO
    root = logging.getLogger()
    saved = root.level
    options.log_handler = install_console_handler(level, stream=err)
    try:
        code: int = options.command(options, out, err)
    except KeyboardInterrupt:
        print("pyrobots-aio: interrupted", file=err)
        return INTERRUPTED
    except SystemExit as exit_:  # SIGTERM, through stop_on_signals
        if exit_.code != TERMINATED:
            raise
        print("pyrobots-aio: terminated", file=err)
        return TERMINATED
    except BrokenPipeError:
        _silence(out)
        return PIPE_CLOSED
    except (PyRobotsError, OSError) as exc:
        print(f"pyrobots-aio: error: {exc}", file=err)
        return 1
    except Exception:  # a bug: show it whole, and fail
        traceback.print_exc(file=err)
        return 1
    finally:
        root.removeHandler(options.log_handler)
        root.setLevel(saved)
    return code


def _silence(out: TextIO) -> None:
    """Point ``out``'s file descriptor at /dev/null: its reader is gone.

    Without it, Python's own flush of standard output at exit fails on the
    closed pipe again and prints ``Exception ignored ... BrokenPipeError``.
    """
    with contextlib.suppress(OSError, ValueError):  # no file descriptor (a StringIO)
        fd = out.fileno()
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
