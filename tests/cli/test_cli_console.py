"""The console log handler: loop time, level colours, short names, the running action."""

from __future__ import annotations

import io
import logging
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import Robot, action
from pyrobots_aio.cli import ConsoleHandler, install_console_handler
from pyrobots_aio.cli._console import short_name

if TYPE_CHECKING:
    from collections.abc import Iterator

log = logging.getLogger("pyrobots_aio.sim.random_walk")


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def handler() -> Iterator[tuple[ConsoleHandler, io.StringIO]]:
    out = io.StringIO()
    installed = ConsoleHandler(out)
    log.addHandler(installed)
    saved = log.level
    log.setLevel(logging.DEBUG)
    yield installed, out
    log.removeHandler(installed)
    log.setLevel(saved)


@action
async def bump(robot: Robot) -> None:
    await robot.sleep(1.5)
    log.info("backing off %.2f m", 0.15)


@pytest.mark.virtual_time
@pytest.mark.asyncio
async def test_a_line_has_the_loop_time_level_logger_and_action(
    handler: tuple[ConsoleHandler, io.StringIO],
) -> None:
    _, out = handler
    async with Robot() as robot:
        await bump(robot)
        log.warning("outside any action")
    assert out.getvalue().splitlines() == [
        "   1.500 INFO    sim.random_walk  bump#1  backing off 0.15 m",
        "   1.500 WARNING sim.random_walk  outside any action",
    ]


def test_without_a_loop_the_time_is_blank_and_tracebacks_follow(
    handler: tuple[ConsoleHandler, io.StringIO],
) -> None:
    _, out = handler
    try:
        raise ValueError("boom")
    except ValueError:
        log.exception("it broke")
    lines = out.getvalue().splitlines()
    assert lines[0] == "         ERROR   sim.random_walk  it broke"
    assert lines[1] == "Traceback (most recent call last):"
    assert lines[-1] == "ValueError: boom"


def test_levels_are_coloured_on_a_terminal_unless_no_color(
    monkeypatch: pytest.MonkeyPatch, handler: tuple[ConsoleHandler, io.StringIO]
) -> None:
    installed, out = handler
    monkeypatch.delenv("NO_COLOR", raising=False)
    log.debug("plain: not a terminal")
    terminal = Terminal()
    installed.stream = terminal
    log.debug("dim")
    log.error("red")
    monkeypatch.setenv("NO_COLOR", "1")
    log.info("no colour wanted")
    installed.colour = True
    log.info("forced")
    assert out.getvalue() == "         DEBUG   sim.random_walk  plain: not a terminal\n"
    assert terminal.getvalue().splitlines() == [
        "         \x1b[2mDEBUG  \x1b[0m sim.random_walk  dim",
        "         \x1b[31mERROR  \x1b[0m sim.random_walk  red",
        "         INFO    sim.random_walk  no colour wanted",
        "         \x1b[32mINFO   \x1b[0m sim.random_walk  forced",
    ]


def test_install_replaces_the_previous_handler_and_sets_the_level() -> None:
    name = "pyrobots_aio.test_install"
    target = logging.getLogger(name)
    first = install_console_handler(logging.DEBUG, logger=name, stream=io.StringIO())
    out = io.StringIO()
    second = install_console_handler(logging.WARNING, logger=name, stream=out)
    try:
        assert [h for h in target.handlers if isinstance(h, ConsoleHandler)] == [second]
        assert first is not second
        assert target.level == logging.WARNING
        target.info("hidden")
        target.warning("shown")
        assert out.getvalue() == "         WARNING test_install  shown\n"
    finally:
        target.removeHandler(second)
        target.setLevel(logging.NOTSET)


def test_the_library_installs_no_handler() -> None:
    import pyrobots_aio.cli
    import pyrobots_aio.recording  # noqa: F401

    for name in ("", "pyrobots_aio"):
        assert not [h for h in logging.getLogger(name).handlers if isinstance(h, ConsoleHandler)]


@pytest.mark.parametrize(
    ("name", "short"),
    [
        ("pyrobots_aio", "pyrobots_aio"),
        ("pyrobots_aio.actions", "actions"),
        ("asyncio", "asyncio"),
        ("myservice.controllers.navigation.planner", "m.c.n.planner"),
        ("myservice.controllers.nav", "m.controllers.nav"),
    ],
)
def test_logger_names_are_shortened(name: str, short: str) -> None:
    assert short_name(name) == short
