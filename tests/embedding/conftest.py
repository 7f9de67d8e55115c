"""Real servers for the embedding tests: an example app in a subprocess on 127.0.0.1.

The server runs as a user runs it (``uvicorn --app-dir examples ...``, ``python
examples/NAME.py --port N``), its output goes to a file, and the test stops it
as a user does, with SIGINT.
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from log_support import without_watchdog

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

EXAMPLES = Path(__file__).parents[2] / "examples"
READY_WITHIN = 60.0  # seconds for the server to listen: imports are slow on a loaded machine
EXIT_WITHIN = 60.0  # seconds for the server to exit after SIGINT
ALARMS = re.compile(
    r"Traceback|Task was destroyed but it is pending|never retrieved|"
    r"\b(?:ERROR|CRITICAL|WARNING)\b"
)
LOG_CONFIG = {  # for uvicorn --log-config: every logger, the app's too, through one handler
    "version": 1,
    "disable_existing_loggers": False,
    "handlers": {"console": {"class": "pyrobots_aio.cli.ConsoleHandler", "colour": False}},
    "root": {"level": "INFO", "handlers": ["console"]},
}


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class Server:
    """A server in a subprocess (``python ARGS``, ``{port}`` replaced); output to ``log``."""

    def __init__(self, args: list[str], log: Path) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.log = log
        with log.open("wb") as out:
            self.process = subprocess.Popen(
                [sys.executable, *(arg.format(port=self.port) for arg in args)],
                stdout=out,
                stderr=subprocess.STDOUT,
                env={**os.environ, "NO_COLOR": "1", "PYTHONUNBUFFERED": "1"},
            )

    def wait_until_listening(self) -> None:
        """Poll the port (bounded) until the server accepts; fail at once if it died."""
        deadline = time.monotonic() + READY_WITHIN
        while time.monotonic() < deadline:
            assert self.process.poll() is None, f"the server exited:\n{self.output()}"
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=1).close()
            except OSError:
                time.sleep(0.05)
            else:
                return
        pytest.fail(f"no server on port {self.port} within {READY_WITHIN} s:\n{self.output()}")

    def interrupt(self) -> None:
        """Ctrl-C, as a user stops the server."""
        self.process.send_signal(signal.SIGINT)

    def wait_for_clean_exit(self) -> str:
        """Wait (bounded) for the server to exit; check it exited cleanly; return its output.

        Clean: exit code 0, nothing alarming printed, and the app's own log says
        no task was left once the robot was out.
        """
        self.process.wait(timeout=EXIT_WITHIN)
        output = self.output()
        assert self.process.returncode == 0, output
        # (a loaded machine can stall the app's loop: the watchdog's report is of the machine)
        assert [line for line in without_watchdog(output) if ALARMS.search(line)] == [], output
        assert "robot stopped; tasks left: none" in output, output
        return output

    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=EXIT_WITHIN)


@pytest.fixture
def serve(tmp_path: Path) -> Iterator[Callable[[list[str]], Server]]:
    """Start a server (``python ARGS``) and wait until it listens; kill it if a test failed."""
    started: list[Server] = []

    def start(args: list[str]) -> Server:
        server = Server(args, tmp_path / f"server-{len(started)}.log")
        started.append(server)
        server.wait_until_listening()
        return server

    yield start
    for server in started:
        server.kill()


@pytest.fixture
def uvicorn_command(tmp_path: Path) -> list[str]:
    """The FastAPI example under uvicorn's own command line, as it is deployed."""
    config = tmp_path / "logging.json"
    config.write_text(json.dumps(LOG_CONFIG))
    return [
        *("-m", "uvicorn", "--app-dir", str(EXAMPLES), "--log-config", str(config)),
        *("--host", "127.0.0.1", "--port", "{port}", "embedded_fastapi:app"),
    ]


@pytest.fixture
def aiohttp_command() -> list[str]:
    """The aiohttp example under ``web.run_app``, as its ``--port`` option runs it."""
    return [str(EXAMPLES / "embedded_aiohttp.py"), "--port", "{port}"]
