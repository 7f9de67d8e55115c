"""Per-robot log levels over the library's module loggers.

The library logs on ``pyrobots_aio.<part>`` loggers and never configures
logging. ``robot.silent()``/``debug()``/``loglevel()`` must affect that robot's
records only, so a robot does not change any logger's level: it owns a
`LogScope`, and the library logs what concerns that robot through it. With no
level set, a scope defers to the loggers (the user's configuration); with a
level set, records of that robot at or above it go to the loggers' handlers,
and those below it are dropped, whatever the loggers' own levels.
"""

from __future__ import annotations

import logging
import sys
from typing import Any

_LEVELS = "DEBUG, INFO, WARNING, ERROR, CRITICAL (or an int)"


def check_level(level: object) -> int:
    """Return ``level`` (an int, or a level name such as ``"DEBUG"``) as an int.

    Raises:
        ValueError: Not a known level name nor a non-negative int.

    Examples:
        >>> check_level("debug"), check_level(30)
        (10, 30)
    """
    if isinstance(level, str):
        number = logging.getLevelNamesMapping().get(level.upper())
        if number is not None:
            return number
    elif isinstance(level, int) and not isinstance(level, bool) and level >= 0:
        return level
    msg = f"unknown log level {level!r}; use one of {_LEVELS}"
    raise ValueError(msg)


class LogScope:
    """The log level of one robot (None: defer to the loggers' configuration).

    Examples:
        >>> scope = LogScope()
        >>> log = scope.logger("pyrobots_aio.actions")
        >>> scope.level = logging.WARNING  # robot.silent(): what goes wrong, nothing else
        >>> log.isEnabledFor(logging.ERROR), log.isEnabledFor(logging.INFO)
        (True, False)
    """

    __slots__ = ("level",)

    def __init__(self) -> None:
        self.level: int | None = None

    def logger(self, name: str) -> ScopedLogger:
        """The logger ``name``, as seen through this scope."""
        return ScopedLogger(self, logging.getLogger(name))

    def __repr__(self) -> str:
        shown = "loggers' own" if self.level is None else logging.getLevelName(self.level)
        return f"<LogScope {shown}>"


class ScopedLogger:
    """A module logger seen through a robot's `LogScope`; the usual methods, ``%s`` lazy."""

    __slots__ = ("_logger", "_scope")

    def __init__(self, scope: LogScope, logger: logging.Logger) -> None:
        self._scope = scope
        self._logger = logger

    @property
    def name(self) -> str:
        """The module logger's name."""
        return self._logger.name

    def isEnabledFor(self, level: int) -> bool:
        """Whether a record at ``level`` would be emitted for this robot."""
        own = self._scope.level
        if own is None:
            return self._logger.isEnabledFor(level)
        return level >= own and not self._logger.disabled

    def log(self, level: int, msg: str, *args: Any, exc_info: Any = None) -> None:
        """Log ``msg % args`` at ``level`` if this robot's level lets it through."""
        if not self.isEnabledFor(level):
            return
        logger = self._logger
        if self._scope.level is None:
            logger.log(level, msg, *args, exc_info=exc_info, stacklevel=3)
            return
        if exc_info is True:
            exc_info = sys.exc_info()
        elif isinstance(exc_info, BaseException):
            exc_info = (type(exc_info), exc_info, exc_info.__traceback__)
        caller = sys._getframe(2)  # the library code that logged (log <- warning <- caller)
        record = logger.makeRecord(
            logger.name,
            level,
            caller.f_code.co_filename,
            caller.f_lineno,
            msg,
            args,
            exc_info,
            caller.f_code.co_name,
        )
        logger.handle(record)  # past the logger's level (this robot's own decides), not filters

    def debug(self, msg: str, *args: Any, exc_info: Any = None) -> None:
        """Log at DEBUG."""
        self.log(logging.DEBUG, msg, *args, exc_info=exc_info)

    def info(self, msg: str, *args: Any, exc_info: Any = None) -> None:
        """Log at INFO."""
        self.log(logging.INFO, msg, *args, exc_info=exc_info)

    def warning(self, msg: str, *args: Any, exc_info: Any = None) -> None:
        """Log at WARNING."""
        self.log(logging.WARNING, msg, *args, exc_info=exc_info)

    def error(self, msg: str, *args: Any, exc_info: Any = None) -> None:
        """Log at ERROR."""
        self.log(logging.ERROR, msg, *args, exc_info=exc_info)

    def exception(self, msg: str, *args: Any) -> None:
        """Log at ERROR with the exception being handled."""
        self.log(logging.ERROR, msg, *args, exc_info=True)

    def __repr__(self) -> str:
        return f"<ScopedLogger {self._logger.name} {self._scope!r}>"
