"""The random walk over ROS 2: `Ros2Robot` drives ``pyrobots-aio sim-node`` in another process.

The very code of ``examples/random_walk.py`` (`pyrobots_aio.sim.random_walk`),
on a robot that it reaches only through ROS 2 topics: ``cmd_vel`` out;
odometry, IR ranges, bumper, cliff and dock state in. The bumper reflex still
preempts the current move and hands control back to the walk.

By default this script starts the sim-node itself (four times faster than
real time, with ``/clock``; its own loop runs at the same rate) and stops it
at the end. To drive a sim-node (or a real robot) of your own, start it in
another shell and pass ``--external``::

    pyrobots-aio sim-node --namespace /robot1 --rate 4
    python examples/random_walk_ros2.py --external --rate 4

Needs the ``ros2`` and ``sim`` extras (``pip install -e ".[sim,ros2]"``).
Discovery stays on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``
unless set); with a sim-node of its own, the script also draws a random
``ROS_DOMAIN_ID`` unless one is set, so it never drives anyone else's robot.
Run: ``python examples/random_walk_ros2.py [--moves N] [--seed N] [--silence SECONDS]``
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys

from pyrobots_aio import PyRobotsError
from pyrobots_aio.cli import install_console_handler
from pyrobots_aio.loops import run_scaled
from pyrobots_aio.ros2 import Ros2Robot
from pyrobots_aio.sim.random_walk import WalkReport, random_walk

COMMAND = [sys.executable, "-m", "pyrobots_aio.cli", "sim-node"]  # pyrobots-aio sim-node


async def main(namespace: str, moves: int, seed: int, rate: float, silence: float) -> WalkReport:
    # odom_timeout is in the loop's (simulated) seconds: the default 0.5 s is a real base's
    # bound, an eighth of a wall-clock second at 4x, which a busy machine starves the
    # sim-node (or this script) of. `silence` wall-clock seconds at any rate instead; the
    # sim-node's own command timeout still stops its wheels if this script goes quiet.
    async with Ros2Robot(namespace=namespace, odom_timeout=silence * rate) as robot:
        return await random_walk(robot, moves=moves, seed=seed)


def start_sim_node(namespace: str, rate: float, silence: float) -> subprocess.Popen[str]:
    """``pyrobots-aio sim-node`` in a subprocess, once it says it is ready.

    Its commands hold ``silence`` wall-clock seconds, as the robot waits for its odometry.

    Raises:
        SystemExit: The sim-node ended before it was ready (it said why, on standard error).
    """
    node = subprocess.Popen(
        [
            *COMMAND,
            *("--namespace", namespace, "--rate", str(rate)),
            *("--cmd-timeout", str(silence * rate)),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert node.stdout is not None
    ready = node.stdout.readline().strip()
    if not ready:  # its own error is above: no robot to drive
        code = node.wait()
        raise SystemExit(f"random_walk_ros2.py: error: the sim-node did not start (exit {code})")
    print(ready, flush=True)
    return node


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--namespace", default="/robot1", help="the robot's ROS 2 namespace (default: /robot1)"
    )
    parser.add_argument(
        "--rate", type=float, default=4.0, help="the sim-node's rate (default: 4, 4x real time)"
    )
    parser.add_argument("--moves", type=int, default=5, help="random moves made (default: 5)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the moves (default: 0)")
    parser.add_argument(
        "--silence",
        type=float,
        default=0.5,
        help="wall-clock seconds the script and its sim-node may go without a word from the "
        "other before odometry counts as stale and the sim-node stops the wheels (default: 0.5; "
        "more on a busy machine)",
    )
    parser.add_argument("--external", action="store_true", help="drive a sim-node of your own")
    options = parser.parse_args()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if not options.external:  # the sim-node inherits it
        os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(1, 101)))
    install_console_handler()
    sim_node = (
        None
        if options.external
        else start_sim_node(options.namespace, options.rate, options.silence)
    )
    try:
        report = run_scaled(
            main,
            *(options.namespace, options.moves, options.seed, options.rate, options.silence),
            rate=options.rate,
        )
    except PyRobotsError as error:  # rclpy missing, a bad namespace: one line, no traceback
        raise SystemExit(f"random_walk_ros2.py: error: {error}") from None
    finally:
        if sim_node is not None:
            sim_node.terminate()
            sim_node.wait()
    print(
        f"{report.moves} moves, {report.bumps} bumps handled, {report.interrupted} moves "
        f"interrupted, {'docked' if report.docked else 'NOT docked'}, "
        f"{report.sim_time:.1f} s simulated"
    )
