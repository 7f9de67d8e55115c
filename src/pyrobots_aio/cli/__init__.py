"""The ``pyrobots-aio`` command, and what the command and examples use around a robot.

Layer: on top; uses only the public API of ``pyrobots_aio``.

Commands::

    pyrobots-aio demo random-walk [--duration SECONDS] [--realtime] [--record PATH] [--seed N]
    pyrobots-aio replay PATH [--timeline OUT.html]
    pyrobots-aio sim-node [--namespace NS] [--rate FACTOR] ...
    pyrobots-aio ros2 interfaces build [PACKAGE ...]

The library never configures logging; a program calls `install_console_handler`
to see its records, coloured, with the time since start and the running action.
`stop_on_signals` makes Ctrl-C and SIGTERM stop a robot program in order.
"""

from pyrobots_aio.robot import SignalStop as SignalStop
from pyrobots_aio.robot import stop_on_signals as stop_on_signals

from ._console import ConsoleHandler as ConsoleHandler
from ._console import install_console_handler as install_console_handler
from ._main import main as main

__all__ = ["ConsoleHandler", "SignalStop", "install_console_handler", "main", "stop_on_signals"]
