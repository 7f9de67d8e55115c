"""The ``pyrobots-aio`` command, and the console log handler the command and examples use.

Layer: on top; uses only the public API of ``pyrobots_aio``.

Commands::

    pyrobots-aio demo random-walk [--duration SECONDS] [--realtime] [--record PATH] [--seed N]
    pyrobots-aio replay PATH [--timeline OUT.html]
    pyrobots-aio sim-node [--namespace NS] [--rate FACTOR] ...

The library never configures logging; a program calls `install_console_handler`
to see its records, coloured, with the loop time and the running action.
"""

from ._console import ConsoleHandler as ConsoleHandler
from ._console import install_console_handler as install_console_handler
from ._main import main as main

__all__ = ["ConsoleHandler", "install_console_handler", "main"]
