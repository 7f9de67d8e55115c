"""``sim-node --robots N``: several simulated robots in one world, each under its namespace.

The robots share one MuJoCo world (``SimWorld(robots=N)``: each starts on its
own dock, the docks 0.5 m apart along the west wall), so they see and bump
into one another; each is a `SimRobot` with its own ROS 2 node and the
profile's topics under its own namespace: ``<namespace>/robot1``,
``<namespace>/robot2`` ... (with one robot, ``<namespace>`` itself, as
before). Only the first robot's node publishes ``/clock``: the world has one
clock.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Sequence

    from pyrobots_aio.sim import SimRobot

__all__ = ["add_robots_argument", "robot_namespaces", "sim_robots", "topics_line"]


def _robot_count(text: str) -> int:
    from pyrobots_aio.sim import SimWorld

    try:
        count = int(text)
    except ValueError:
        count = 0
    if not 0 < count <= SimWorld.MAX_ROBOTS:
        msg = f"expected a whole number of robots from 1 to {SimWorld.MAX_ROBOTS}, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return count


def add_robots_argument(node: argparse.ArgumentParser) -> None:
    """Add ``--robots`` to the ``sim-node`` command."""
    node.add_argument(
        "--robots",
        type=_robot_count,
        default=1,
        metavar="N",
        help="simulate N robots in one world (default: 1), each on its own dock, under "
        "NAMESPACE/robot1, NAMESPACE/robot2 ...; one /clock",
    )


def robot_namespaces(namespace: str, robots: int) -> list[str]:
    """Each robot's namespace: ``namespace`` for one robot, else ``namespace/robotK``.

    Examples:
        >>> robot_namespaces("/", 2)
        ['/robot1', '/robot2']
        >>> robot_namespaces("/lab", 1)
        ['/lab']
    """
    if robots == 1:
        return [namespace]
    return [f"{namespace.rstrip('/')}/robot{k}" for k in range(1, robots + 1)]


def sim_robots(options: argparse.Namespace) -> list[tuple[SimRobot, str]]:
    """The robots the options ask for, in one world, each with its namespace."""
    from pyrobots_aio.sim import SimRobot, SimWorld

    world = SimWorld(seed=options.seed, robots=options.robots)
    namespaces = robot_namespaces(options.namespace, options.robots)
    return [
        (
            SimRobot(
                world=body,
                realtime=True,
                control_rate=options.control_rate,
                stall_timeout=options.stall_timeout,
            ),
            namespace,
        )
        for body, namespace in zip(world.robots, namespaces, strict=True)
    ]


def topics_line(topics: int, namespaces: Sequence[str]) -> str:
    """How many topics the ready line counts, and where."""
    if len(namespaces) == 1:
        return f"{topics} topics under {namespaces[0]}"
    return f"{topics} topics under each of {', '.join(namespaces)}"
