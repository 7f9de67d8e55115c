"""The console log handler: loop time, level colours, short names, the running action."""

from __future__ import annotations

import asyncio
import io
import logging
import subprocess
import sys
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
        "    1.500  INFO    sim.random_walk  bump#1  backing off 0.15 m",
        "    1.500  WARNING sim.random_walk  outside any action",
    ]


class BootClockLoop(asyncio.SelectorEventLoop):
    """An ordinary loop whose clock reads as a real one may: seconds since the machine booted."""

    now = 86_400.0

    def time(self) -> float:
        return self.now


async def _log_twice(loop: BootClockLoop) -> None:
    log.info("first")
    loop.now += 2.5
    log.info("2.5 s later")


def test_on_an_ordinary_loop_times_count_from_the_first_record(
    handler: tuple[ConsoleHandler, io.StringIO],
) -> None:
    # Before: the loop's raw clock (86400.000, 86402.500) beside the demo's times since start.
    _, out = handler
    with asyncio.Runner(loop_factory=BootClockLoop) as runner:
        runner.run(_log_twice(runner.get_loop()))  # type: ignore[arg-type]
    assert out.getvalue().splitlines() == [
        "    0.000  INFO    sim.random_walk  first",
        "    2.500  INFO    sim.random_walk  2.5 s later",
    ]


def test_a_set_start_counts_from_there(handler: tuple[ConsoleHandler, io.StringIO]) -> None:
    installed, out = handler
    installed.start = 86_000.0  # what the demo sets: the robot's start on the loop's clock
    with asyncio.Runner(loop_factory=BootClockLoop) as runner:
        runner.run(_log_twice(runner.get_loop()))  # type: ignore[arg-type]
    assert out.getvalue().splitlines() == [
        "  400.000  INFO    sim.random_walk  first",
        "  402.500  INFO    sim.random_walk  2.5 s later",
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
    assert lines[0] == "           ERROR   sim.random_walk  it broke"
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
    assert out.getvalue() == "           DEBUG   sim.random_walk  plain: not a terminal\n"
    assert terminal.getvalue().splitlines() == [
        "           \x1b[2mDEBUG  \x1b[0m sim.random_walk  dim",
        "           \x1b[31mERROR  \x1b[0m sim.random_walk  red",
        "           INFO    sim.random_walk  no colour wanted",
        "           \x1b[32mINFO   \x1b[0m sim.random_walk  forced",
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
        assert out.getvalue() == "           WARNING test_install  shown\n"
    finally:
        target.removeHandler(second)
        target.setLevel(logging.NOTSET)


NO_HANDLER_SCRIPT = """
import asyncio, importlib, logging, pkgutil

def handlers():
    # the root's and pyrobots_aio's handlers, and those of any pyrobots_aio.* logger
    found = {"": [], "pyrobots_aio": []}
    for name in sorted({"", "pyrobots_aio", *logging.root.manager.loggerDict}):
        if name in ("", "pyrobots_aio") or name.startswith("pyrobots_aio."):
            for handler in logging.getLogger(name).handlers:
                found.setdefault(name, []).append(repr(handler))
    return found

before = handlers()
import pyrobots_aio
for module in pkgutil.walk_packages(pyrobots_aio.__path__, "pyrobots_aio."):
    if not module.name.endswith("__main__"):  # that one runs the command
        importlib.import_module(module.name)

from pyrobots_aio import Robot, action
from pyrobots_aio.sim import SimRobot, run

@action
async def nap(robot):
    await robot.sleep(0.1)
    logging.getLogger("pyrobots_aio.test").warning("a record")

async def plain():
    async with Robot() as robot:
        await nap(robot)

async def simulated():
    async with SimRobot() as robot:
        await nap(robot)
        await robot.drive_distance(0.05)

asyncio.run(plain())
run(simulated)
print(before)
print(handlers())
"""


def test_the_library_installs_no_handler() -> None:
    # A fresh interpreter: what this test session imported and configured does not count.
    done = subprocess.run(
        [sys.executable, "-c", NO_HANDLER_SCRIPT],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "{'': [], 'pyrobots_aio': []}",  # before importing the library
        "{'': [], 'pyrobots_aio': []}",  # after importing all of it, running Robot and SimRobot
    ]
    # Each run's record reached logging's last resort: nobody configured logging.
    assert done.stderr == "a record\n" * 2


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
