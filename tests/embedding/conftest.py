"""Real servers for the embedding tests: an example app in a subprocess on 127.0.0.1.

The server runs as a user runs it (``python examples/NAME.py --port N``), its
output goes to a file, and the test stops it as a user does, with SIGINT.
"""

from __future__ import annotations

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

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

EXAMPLES = Path(__file__).parents[2] / "examples"
READY_WITHIN = 60.0  # seconds for the server to listen: imports are slow on a loaded machine
EXIT_WITHIN = 60.0  # seconds for the server to exit after SIGINT
ALARMS = re.compile(
    r"Traceback|Task was destroyed but it is pending|never retrieved|"
    r"\b(?:ERROR|CRITICAL|WARNING)\b"
)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class Server:
    """One example app serving in a subprocess; its combined output goes to ``log``."""

    def __init__(self, name: str, log: Path) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.log = log
        with log.open("wb") as out:
            self.process = subprocess.Popen(
                [sys.executable, str(EXAMPLES / f"{name}.py"), "--port", str(self.port)],
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
        assert [line for line in output.splitlines() if ALARMS.search(line)] == [], output
        assert "robot stopped; tasks left: none" in output, output
        return output

    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=EXIT_WITHIN)


@pytest.fixture
def serve(tmp_path: Path) -> Iterator[Callable[[str], Server]]:
    """Start ``examples/NAME.py --port N`` and wait until it listens; kill it if a test failed."""
    started: list[Server] = []

    def start(name: str) -> Server:
        server = Server(name, tmp_path / f"{name}.log")
        started.append(server)
        server.wait_until_listening()
        return server

    yield start
    for server in started:
        server.kill()
