"""The console log handler: coloured levels, short logger names, loop time, action names.

The library never installs it; the ``pyrobots-aio`` command and the examples
do, through `install_console_handler`. A line reads::

    12.340 INFO    sim.random_walk  move#7  move 3 interrupted: preempted by ...

that is: the loop time (``robot.time()``: simulation time in lockstep; blank
when no loop runs), the level, the logger name without its ``pyrobots_aio.``
prefix, the running action (``name#id``, from
`pyrobots_aio.actions.current_action`) and the message.
"""

from __future__ import annotations

import asyncio
import logging
import os
import sys
from typing import TYPE_CHECKING, Protocol

from pyrobots_aio.actions import current_action

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


def wants_colour(stream: Stream) -> bool:
    """Colour on a terminal unless ``NO_COLOR`` is set to something (https://no-color.org)."""
    if os.environ.get("NO_COLOR"):
        return False
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty())


def short_name(name: str, width: int = NAME_WIDTH) -> str:
    """Drop the ``pyrobots_aio.`` prefix; abbreviate leading parts of a long dotted name.

    Example:
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


def _loop_time() -> float | None:
    try:
        return asyncio.get_running_loop().time()
    except RuntimeError:
        return None


class ConsoleHandler(logging.Handler):
    """A `logging.Handler` for people at a terminal.

    Args:
        stream: Where to write (default: ``sys.stderr`` at the time of each record).
        level: The handler's level.
        colour: Colour the level names; None decides per stream: only on a
            terminal, and never when ``NO_COLOR`` is set.

    Example:
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
    ) -> None:
        super().__init__(level)
        self._stream = stream
        self.colour = colour
        self._plain = logging.Formatter()

    @property
    def stream(self) -> Stream:
        """The stream written to (settable; None: ``sys.stderr`` at the time of each record)."""
        return self._stream if self._stream is not None else sys.stderr

    @stream.setter
    def stream(self, stream: Stream | None) -> None:
        self._stream = stream

    def format(self, record: logging.LogRecord) -> str:
        """``time LEVEL logger  action  message`` (and the traceback, if any)."""
        now = _loop_time()
        stamp = f"{now:8.3f}" if now is not None else " " * 8
        level = f"{record.levelname:<7}"
        colour = self.colour if self.colour is not None else wants_colour(self.stream)
        if colour:
            level = f"{LEVEL_COLOURS.get(record.levelno, '')}{level}{RESET}"
        handle = current_action.get()
        who = f"  {handle.name}#{handle.id}" if handle is not None else ""
        text = f"{stamp} {level} {short_name(record.name)}{who}  {record.getMessage()}"
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
) -> ConsoleHandler:
    """Log to the console through a `ConsoleHandler`, replacing one installed before.

    Args:
        level: The level of ``logger`` (and so of what is shown).
        logger: The logger to attach to (default: the root logger, so the
            program's own loggers show too).
        stream: Where to write (default: standard error).
        colour: See `ConsoleHandler`.

    Returns:
        The handler, to remove it later (``logging.getLogger().removeHandler(h)``).

    Example:
        >>> import logging
        >>> from pyrobots_aio.cli import install_console_handler
        >>> handler = install_console_handler(logging.DEBUG)  # doctest: +SKIP
    """
    target = logging.getLogger(logger)
    for old in [h for h in target.handlers if isinstance(h, ConsoleHandler)]:
        target.removeHandler(old)
    handler = ConsoleHandler(stream, colour=colour)
    target.addHandler(handler)
    target.setLevel(level)
    return handler
