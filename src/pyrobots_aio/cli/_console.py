"""The console log handler: coloured levels, short logger names, time since start, actions.

The library never installs it; the ``pyrobots-aio`` command and the examples
do, through `install_console_handler`. A line reads::

       12.340  INFO    sim.random_walk  move#7  move 3 interrupted: preempted by ...

that is: the seconds since start on the loop's clock (blank when no loop
runs), the level, the logger name without its ``pyrobots_aio.`` prefix, the
running action (``name#id``, from `pyrobots_aio.actions.current_action`) and
the message. The time column is as wide as the demo's event lines', so that
the two kinds of line align.

Since start: since `ConsoleHandler.start` when it is set (the demo sets it
to the robot's start); else, on a virtual-time loop, its clock as it is
(simulation time, which starts at 0), and on an ordinary loop, whose clock
counts from an arbitrary point (often the machine's boot), since the first
record logged on that loop.
"""

from __future__ import annotations

import asyncio
import logging
import os
import sys
import weakref
from typing import TYPE_CHECKING, Protocol

from pyrobots_aio.actions import current_action
from pyrobots_aio.loops import is_virtual

if TYPE_CHECKING:
    from collections.abc import Mapping


class Stream(Protocol):
    """Where a `ConsoleHandler` writes: a text stream (``isatty`` is optional)."""

    def write(self, text: str, /) -> int:
        """Write ``text``."""

    def flush(self) -> None:
        """Flush what was written."""


RESET = "\x1b[0m"
LEVEL_COLOURS: Mapping[int, str] = {
    logging.DEBUG: "\x1b[2m",  # dim
    logging.INFO: "\x1b[32m",  # green
    logging.WARNING: "\x1b[33m",  # yellow
    logging.ERROR: "\x1b[31m",  # red
    logging.CRITICAL: "\x1b[1;31m",  # bold red
}
"""ANSI colour of each level's name."""
NAME_WIDTH = 18
TIME_WIDTH = 9
"""Characters of the time column (``{:9.3f}``), the demo's event lines' included."""


def wants_colour(stream: Stream) -> bool:
    """Colour on a terminal unless ``NO_COLOR`` is set to something (https://no-color.org)."""
    if os.environ.get("NO_COLOR"):
        return False
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def short_name(name: str, width: int = NAME_WIDTH) -> str:
    """Drop the ``pyrobots_aio.`` prefix; abbreviate leading parts of a long dotted name.

    Examples:
        >>> short_name("pyrobots_aio.sim.random_walk")
        'sim.random_walk'
        >>> short_name("myservice.controllers.navigation.planner")
        'm.c.n.planner'
    """
    if name.startswith("pyrobots_aio."):
        name = name[len("pyrobots_aio.") :]
    parts = name.split(".")
    for i in range(len(parts) - 1):
        if len(".".join(parts)) <= width:
            break
        parts[i] = parts[i][:1]
    return ".".join(parts)


def format_time(seconds: float | None) -> str:
    """The time column: seconds with milliseconds, right-aligned; blank for None.

    Examples:
        >>> format_time(12.34)
        '   12.340'
        >>> format_time(None) == " " * TIME_WIDTH
        True
    """
    return " " * TIME_WIDTH if seconds is None else f"{seconds:{TIME_WIDTH}.3f}"


class ConsoleHandler(logging.Handler):
    """A `logging.Handler` for people at a terminal.

    Args:
        stream: Where to write (default: ``sys.stderr`` at the time of each record).
        level: The handler's level.
        colour: Colour the level names; None decides per stream: only on a
            terminal, and never when ``NO_COLOR`` is set.
        start: The loop time shown as 0 (settable; see the module for None).

    Examples:
        >>> import io, logging
        >>> out = io.StringIO()
        >>> log = logging.getLogger("pyrobots_aio.demo")
        >>> log.addHandler(ConsoleHandler(out))
        >>> log.warning("wheels %s", "stalled")
        >>> print(out.getvalue(), end="")
                   WARNING demo  wheels stalled
        >>> log.handlers.clear()
    """

    def __init__(
        self,
        stream: Stream | None = None,
        level: int | str = logging.NOTSET,
        *,
        colour: bool | None = None,
        start: float | None = None,
    ) -> None:
        super().__init__(level)
        self._stream = stream
        self.colour = colour
        self.start = start
        self._plain = logging.Formatter()
        self._loop: weakref.ref[asyncio.AbstractEventLoop] | None = None
        self._origin = 0.0

    @property
    def stream(self) -> Stream:
        """The stream written to (settable; None: ``sys.stderr`` at the time of each record)."""
        return self._stream if self._stream is not None else sys.stderr

    @stream.setter
    def stream(self, stream: Stream | None) -> None:
        self._stream = stream

    def since_start(self) -> float | None:
        """Seconds since start on the running loop's clock (None when no loop runs)."""
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            return None
        now = loop.time()
        if self.start is not None:
            return now - self.start
        if self._loop is None or self._loop() is not loop:  # a loop seen for the first time
            self._loop = weakref.ref(loop)
            self._origin = 0.0 if is_virtual(loop) else now
        return now - self._origin

    def format(self, record: logging.LogRecord) -> str:
        """``time  LEVEL logger  action  message`` (and the traceback, if any)."""
        stamp = format_time(self.since_start())
        level = f"{record.levelname:<7}"
        colour = self.colour if self.colour is not None else wants_colour(self.stream)
        if colour:
            level = f"{LEVEL_COLOURS.get(record.levelno, '')}{level}{RESET}"
        handle = current_action.get()
        who = f"  {handle.name}#{handle.id}" if handle is not None else ""
        text = f"{stamp}  {level} {short_name(record.name)}{who}  {record.getMessage()}"
        if record.exc_info:
            text += "\n" + self._plain.formatException(record.exc_info)
        if record.stack_info:
            text += "\n" + self._plain.formatStack(record.stack_info)
        return text

    def emit(self, record: logging.LogRecord) -> None:
        """Write one record."""
        try:
            stream = self.stream
            stream.write(self.format(record) + "\n")
            stream.flush()
        except Exception:
            self.handleError(record)


def install_console_handler(
    level: int | str = logging.INFO,
    *,
    logger: str | None = None,
    stream: Stream | None = None,
    colour: bool | None = None,
    start: float | None = None,
) -> ConsoleHandler:
    """Log to the console through a `ConsoleHandler`, replacing one installed before.

    Args:
        level: The level of ``logger`` (and so of what is shown).
        logger: The logger to attach to (default: the root logger, so the
            program's own loggers show too).
        stream: Where to write (default: standard error).
        colour: See `ConsoleHandler`.
        start: See `ConsoleHandler`.

    Returns:
        The handler, to remove it later (``logging.getLogger().removeHandler(h)``).

    Examples:
        >>> import logging
        >>> from pyrobots_aio.cli import install_console_handler
        >>> handler = install_console_handler(logging.DEBUG)  # doctest: +SKIP
    """
    target = logging.getLogger(logger)
    for old in [h for h in target.handlers if isinstance(h, ConsoleHandler)]:
        target.removeHandler(old)
    handler = ConsoleHandler(stream, colour=colour, start=start)
    target.addHandler(handler)
    target.setLevel(level)
    return handler
