"""A plain rclpy Create 3 program, as Create 3 users write them, run against ``sim-node``.

Nothing of pyrobots_aio in the robot's code: action clients for ``undock``,
``drive_distance``, ``rotate_angle`` and ``dock`` (irobot_create_msgs), a
``hazard_detection`` subscription whose bump cancels the current forward
drive, and a ``MultiThreadedExecutor`` spinning on a thread while the main
thread sends goals one after the other. It undocks, wanders (a bump cancels
the drive; it backs off and turns away), and docks.

By default it starts ``pyrobots-aio sim-node --profile create3`` itself (four
times faster than real time) and stops it at the end. To drive a sim-node
(or a Create 3) of your own, pass ``--external``::

    pyrobots-aio sim-node --namespace /robot1 --profile create3
    python examples/create3_walk.py --external --namespace /robot1

Needs the ``ros2`` and ``sim`` extras and the Create 3's interfaces
(``pyrobots-aio ros2 interfaces build``). Discovery stays on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` unless set); with a sim-node of
its own it also draws a random ``ROS_DOMAIN_ID`` unless one is set.
Run: ``python examples/create3_walk.py [--moves N] [--seed N]``
"""

from __future__ import annotations

import argparse
import math
import os
import random
import subprocess
import sys
import threading
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus
from irobot_create_msgs.action import Dock, DriveDistance, RotateAngle, Undock
from irobot_create_msgs.msg import HazardDetection, HazardDetectionVector
from rclpy.action import ActionClient
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data

WAIT = 60.0  # seconds any one answer of the robot may take
ENDED_BY_AN_OBSTACLE = (GoalStatus.STATUS_CANCELED, GoalStatus.STATUS_ABORTED)


class Create3Walker(Node):
    """Undock, wander with bump-cancelled drives, dock: one goal at a time."""

    def __init__(self, namespace: str) -> None:
        super().__init__("create3_walker", namespace=namespace)
        group = ReentrantCallbackGroup()
        self.undock_client = ActionClient(self, Undock, "undock", callback_group=group)
        self.drive_client = ActionClient(
            self, DriveDistance, "drive_distance", callback_group=group
        )
        self.rotate_client = ActionClient(self, RotateAngle, "rotate_angle", callback_group=group)
        self.dock_client = ActionClient(self, Dock, "dock", callback_group=group)
        self.create_subscription(
            HazardDetectionVector,
            "hazard_detection",
            self.on_hazards,
            qos_profile_sensor_data,
            callback_group=group,
        )
        self.lock = threading.Lock()
        self.forward_goal: Any = None  # the forward drive a bump cancels
        self.cancelled_by_bumps = 0

    def on_hazards(self, message: HazardDetectionVector) -> None:
        if not any(d.type == HazardDetection.BUMP for d in message.detections):
            return
        with self.lock:
            goal, self.forward_goal = self.forward_goal, None
        if goal is not None:
            self.get_logger().info("bump: cancelling the drive")
            self.cancelled_by_bumps += 1
            goal.cancel_goal_async()

    def run(self, client: ActionClient, goal: Any, *, forward: bool = False) -> Any:
        """Send ``goal`` and wait for its result (the executor's threads answer)."""
        if not client.wait_for_server(timeout_sec=WAIT):
            raise SystemExit(f"create3_walk.py: error: no action server for {goal}")
        accepted = wait(client.send_goal_async(goal))
        if not accepted.accepted:
            raise SystemExit(f"create3_walk.py: error: the robot rejected {goal}")
        if forward:
            with self.lock:
                self.forward_goal = accepted
        result = wait(accepted.get_result_async())
        with self.lock:
            self.forward_goal = None
        return result

    def walk(self, moves: int, seed: int) -> bool:
        chance = random.Random(seed)
        self.run(self.undock_client, Undock.Goal())
        for _ in range(moves):
            drive = DriveDistance.Goal(distance=chance.uniform(0.5, 1.5), max_translation_speed=0.3)
            # Cancelled on a bump, or aborted by the base (stalled against something): back off.
            if self.run(self.drive_client, drive, forward=True).status in ENDED_BY_AN_OBSTACLE:
                self.run(self.drive_client, DriveDistance.Goal(distance=-0.15))
            turn = chance.uniform(math.pi / 4, math.pi) * chance.choice((-1, 1))
            self.run(self.rotate_client, RotateAngle.Goal(angle=turn, max_rotation_speed=1.0))
        for _ in range(3):  # a bump on the way may leave it off its dock: turn, try again
            if self.run(self.dock_client, Dock.Goal()).result.is_docked:
                return True
            self.run(self.rotate_client, RotateAngle.Goal(angle=math.pi / 2))
        return False


def wait(future: Any) -> Any:
    """The result of an rclpy future that the executor's threads complete."""
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    if not done.wait(WAIT):
        raise SystemExit("create3_walk.py: error: the robot did not answer")
    return future.result()


def start_sim_node(namespace: str) -> subprocess.Popen[str]:
    """``pyrobots-aio sim-node --profile create3`` (4x real time), once it says it is ready."""
    command = [sys.executable, "-m", "pyrobots_aio.cli", "sim-node", "--profile", "create3"]
    node = subprocess.Popen(
        [*command, "--namespace", namespace, "--rate", "4"], stdout=subprocess.PIPE, text=True
    )
    assert node.stdout is not None
    ready = node.stdout.readline().strip()
    if not ready:
        raise SystemExit(f"create3_walk.py: error: the sim-node did not start (exit {node.wait()})")
    print(ready, flush=True)
    return node


def main(namespace: str, moves: int, seed: int) -> int:
    rclpy.init()
    walker = Create3Walker(namespace)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(walker)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        docked = walker.walk(moves, seed)
    finally:
        executor.shutdown()
        spinner.join()
        walker.destroy_node()
        rclpy.try_shutdown()
    print(
        f"{moves} moves, {walker.cancelled_by_bumps} drives cancelled by bumps, "
        f"{'docked' if docked else 'NOT docked'}"
    )
    return 0 if docked else 1


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--namespace", default="/robot1", help="the robot's ROS 2 namespace (default: /robot1)"
    )
    parser.add_argument("--moves", type=int, default=6, help="drives and turns made (default: 6)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the moves (default: 0)")
    parser.add_argument("--external", action="store_true", help="drive a robot of your own")
    options = parser.parse_args()
    from pyrobots_aio.cli import install_console_handler  # the starter's part, not the robot's

    install_console_handler()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if not options.external:  # the sim-node inherits it
        os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(1, 101)))
    sim_node = None if options.external else start_sim_node(options.namespace)
    try:
        code = main(options.namespace, options.moves, options.seed)
    finally:
        if sim_node is not None:
            sim_node.terminate()
            sim_node.wait()
    sys.exit(code)
