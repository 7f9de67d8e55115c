"""Chromium driven over the DevTools protocol on a pipe, for the replay page's browser tests.

``--remote-debugging-pipe`` makes chromium read commands on its fd 3 and write
answers and events on its fd 4, each a JSON message ended by a NUL byte: no
socket, no extra package. Mouse input goes through ``Input.dispatchMouseEvent``,
so that the page gets real, trusted events (moves, wheel, drag), as from a
person's mouse, and ``evaluate`` reads back what the page shows.
"""

from __future__ import annotations

import fcntl
import json
import os
import select
import subprocess
import time
from typing import TYPE_CHECKING, Any, Self

if TYPE_CHECKING:
    from pathlib import Path
    from types import TracebackType

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--hide-scrollbars",
)
"""A quiet headless chromium: no network of its own, no first-run pages."""
HANG_GUARD = 90.0
"""Seconds without the answer awaited before the test fails (a hang guard, not a timing)."""


def _above_4(fds: tuple[int, int]) -> tuple[int, int]:
    """The pipe's ends moved above 4, so that making them the child's 3 and 4 clobbers neither."""
    moved = (fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 5) for fd in fds)
    first, second = moved
    for fd in fds:
        os.close(fd)
    return first, second


class BrowserError(AssertionError):
    """The browser answered with an error, threw in the page, or went silent."""


class Page:
    """One page (tab) of a `Browser`, at a viewport of ``width`` by ``height`` CSS pixels."""

    def __init__(self, browser: Browser, session: str) -> None:
        self.browser = browser
        self.session = session

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        return self.browser.call(method, params, self.session)

    def evaluate(self, expression: str) -> Any:
        """The value of the JavaScript ``expression`` in the page (JSON values only)."""
        answer = self.call("Runtime.evaluate", expression=expression, returnByValue=True)
        if "exceptionDetails" in answer:
            raise BrowserError(f"{expression!r} threw: {answer['exceptionDetails']}")
        return answer["result"].get("value")

    def mouse(self, kind: str, x: float, y: float, **more: Any) -> None:
        """A mouse event at (x, y), viewport CSS pixels: mouseMoved, mouseWheel, mousePressed..."""
        self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, **more)

    def errors(self) -> list[dict[str, Any]]:
        """What the page threw so far (``Runtime.exceptionThrown``)."""
        return [e for e in self.browser.events if e.get("method") == "Runtime.exceptionThrown"]


class Browser:
    """A headless chromium on a DevTools pipe; a context manager that stops it."""

    def __init__(self, chromium: str, profile: Path) -> None:
        self.events: list[dict[str, Any]] = []
        self._next = 0
        self._buffer = b""
        ours_in, theirs_out = _above_4(os.pipe())  # chromium writes on its fd 4
        theirs_in, ours_out = _above_4(os.pipe())  # chromium reads on its fd 3
        command = [
            chromium,
            *FLAGS,
            "--remote-debugging-pipe",
            f"--user-data-dir={profile}",
            "about:blank",
        ]
        self._process = subprocess.Popen(
            # bash, not sh: dash redirects only the descriptors 0 to 9.
            ["bash", "-c", f'exec "$0" "$@" 3<&{theirs_in} 4>&{theirs_out}', *command],
            pass_fds=(theirs_in, theirs_out),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        os.close(theirs_in)
        os.close(theirs_out)
        self._in, self._out = ours_in, ours_out

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        try:
            self.call("Browser.close")
        except (BrowserError, OSError):
            pass  # already gone: killed below
        finally:
            try:
                self._process.wait(timeout=HANG_GUARD)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
            os.close(self._in)
            os.close(self._out)

    def call(
        self, method: str, params: dict[str, Any] | None = None, session: str | None = None
    ) -> dict[str, Any]:
        """Send one command and wait for its answer (events met meanwhile are kept)."""
        self._next += 1
        message: dict[str, Any] = {"id": self._next, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        os.write(self._out, json.dumps(message).encode() + b"\0")
        answer = self._receive(lambda m: m.get("id") == self._next)
        if "error" in answer:
            raise BrowserError(f"{method}: {answer['error']}")
        result: dict[str, Any] = answer.get("result", {})
        return result

    def wait_event(self, method: str) -> dict[str, Any]:
        """The first event called ``method`` (already received or next)."""
        for event in self.events:
            if event.get("method") == method:
                self.events.remove(event)
                return event
        return self._receive(lambda m: m.get("method") == method, keep=False)

    def open(self, uri: str, width: int, height: int) -> Page:
        """A new page showing ``uri`` once loaded, its script errors recorded."""
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        attached = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})
        page = Page(self, attached["sessionId"])
        metrics = {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}
        page.call("Emulation.setDeviceMetricsOverride", **metrics)
        page.call("Runtime.enable")
        page.call("Page.enable")
        page.call("Page.navigate", url=uri)
        self.wait_event("Page.loadEventFired")
        return page

    def _receive(self, wanted: Any, *, keep: bool = True) -> dict[str, Any]:
        deadline = time.monotonic() + HANG_GUARD
        while True:
            while b"\0" in self._buffer:
                raw, self._buffer = self._buffer.split(b"\0", 1)
                message: dict[str, Any] = json.loads(raw)
                if wanted(message):
                    return message
                if keep or "method" in message:
                    self.events.append(message)
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._in], [], [], left)[0]:
                raise BrowserError(f"no answer from the browser in {HANG_GUARD:.0f} s")
            chunk = os.read(self._in, 1 << 20)
            if not chunk:
                raise BrowserError("the browser closed its pipe")
            self._buffer += chunk
