"""``pyrobots-aio sim-node``: the simulated robot as a ROS 2 node.

A `SimRobot` (real time, or ``--rate`` times faster) with a ROS 2 node
(`pyrobots_aio.ros2.attach_ros2`) that publishes its sensors every control
tick and drives it from ``cmd_vel``; any ROS 2 tool sees it, and a robot in
another process (or on another machine) can drive it. Topic names are
relative, so ``--namespace /robot1`` puts them under ``/robot1``; several
nodes run side by side under different namespaces. Ctrl-C (SIGINT) or
SIGTERM stops it cleanly (exit code 0).

============================  ============================  =========================
topic                         type                          QoS
============================  ============================  =========================
``cmd_vel`` (in)              geometry_msgs/msg/Twist       default (reliable, 10)
``odom``                      nav_msgs/msg/Odometry         default
``ir_<position>`` (7)         sensor_msgs/msg/Range         sensor_data (best effort)
``bumper``                    std_msgs/msg/Bool             default
``bumper_left``/``_right``    std_msgs/msg/Bool             default
``cliff_<position>`` (4)      std_msgs/msg/Bool             default
``docked``                    std_msgs/msg/Bool             default
``battery_state``             sensor_msgs/msg/BatteryState  default
``/clock`` (``--rate`` ≠ 1)   rosgraph_msgs/msg/Clock       default
``/diagnostics``              diagnostic_msgs/msg/...Array  default, 1 Hz
============================  ============================  =========================

- ``cmd_vel``: ``linear.x`` (m/s) and ``angular.z`` (rad/s); a command holds
  for ``--cmd-timeout`` seconds (0.5), then the wheels stop, as a real base's
  safety timeout does.
- ``odom``: the wheel odometry (frame ``odom``, child ``base_link``), pose
  and measured twist.
- ``ir_<position>``: one ``Range`` per IR rangefinder (``INFRARED``, a single
  ray: ``field_of_view`` 0, ``max_range`` the sensor's range, ``+inf`` when
  nothing is in range, as REP 117 asks; frame ``ir_<position>``).
- Bumper and cliff sensors are ``std_msgs/Bool``: True while the bumper is
  pressed, True while a cliff sensor sees no floor. ``docked`` is True on the dock.
- Stamps: the system clock in real time; the simulation's clock (which
  ``/clock`` carries, from 0) when ``--rate`` is not 1.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import signal
from typing import TYPE_CHECKING, Any, TextIO

from pyrobots_aio.loops import run_scaled

if TYPE_CHECKING:
    from collections.abc import Mapping

    from pyrobots_aio.ros2 import Ros2Node
    from pyrobots_aio.sim import SimRobot


def positive(text: str) -> float:
    """Argparse type: a positive, finite number."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0 < value < math.inf:
        msg = f"expected a positive number, got {text!r}"
        raise argparse.ArgumentTypeError(msg)
    return value


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``sim-node`` command."""
    node = commands.add_parser(
        "sim-node",
        help="run the simulated robot as a ROS 2 node",
        description="Run the simulated robot as a ROS 2 node: cmd_vel in; odom, IR ranges, "
        "bumper, cliff and dock state out (see the README's ROS 2 section for the topics). "
        "Needs the ros2 and sim extras. Ctrl-C stops it.",
    )
    node.add_argument("--name", default="sim_node", help="the node's name (default: sim_node)")
    node.add_argument(
        "--namespace", default="/", help="the node's namespace, e.g. /robot1 (default: /)"
    )
    node.add_argument(
        "--rate",
        type=positive,
        default=1.0,
        metavar="FACTOR",
        help="simulated seconds per wall-clock second (default: 1, real time); any other "
        "rate publishes /clock",
    )
    node.add_argument(
        "--control-rate",
        type=positive,
        default=50.0,
        metavar="HZ",
        help="control ticks per simulated second: sensors are published at this rate (default: 50)",
    )
    node.add_argument(
        "--cmd-timeout",
        type=positive,
        default=0.5,
        metavar="SECONDS",
        help="stop the wheels when no cmd_vel came for this long (default: 0.5)",
    )
    node.add_argument("--seed", type=int, default=0, help="seeds the IR noise (default: 0)")
    node.set_defaults(command=run_sim_node)


class SimNode:
    """The ROS 2 face of a running simulated robot: sensors out every tick, ``cmd_vel`` in."""

    def __init__(self, robot: SimRobot, ros2: Ros2Node, *, sim_clock: bool, cmd_timeout: float):
        from builtin_interfaces.msg import Time
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import BatteryState, Range
        from std_msgs.msg import Bool

        self._types = (Time, Odometry, Range, Bool, BatteryState, Clock)
        self.robot, self.ros2 = robot, ros2
        self._cmd_timeout = cmd_timeout
        self._stop_timer: asyncio.TimerHandle | None = None
        keys = robot.world.state_keys
        self._ir = _ir_ranges(robot)
        self._flags = [k for k in keys if k.startswith(("bumper", "cliff_")) or k == "docked"]
        self._odom = ros2.publisher("odom", Odometry)
        self._ranges = {k: ros2.publisher(k, Range, qos="sensor_data") for k in self._ir}
        self._bools = {k: ros2.publisher(k, Bool) for k in self._flags}
        self._battery = ros2.publisher("battery_state", BatteryState)
        self._clock = ros2.publisher("/clock", Clock) if sim_clock else None
        self._sim_clock = sim_clock
        self._cmd = ros2.subscribe("cmd_vel", Twist, callback=self._on_cmd_vel)
        self._state = robot.state.subscribe(self._publish, keys=keys)
        self.topics = sorted(
            p.topic for p in (self._odom, *self._ranges.values(), *self._bools.values())
        )

    def close(self) -> None:
        """Stop publishing and listening (the robot's shutdown closes the ROS side)."""
        self._state.close()
        if self._stop_timer is not None:
            self._stop_timer.cancel()

    def _on_cmd_vel(self, twist: Any) -> None:
        self.robot.drive(twist.linear.x, twist.angular.z)
        if self._stop_timer is not None:
            self._stop_timer.cancel()
        self._stop_timer = asyncio.get_running_loop().call_later(self._cmd_timeout, self.robot.stop)

    def _stamp(self) -> Any:
        if not self._sim_clock:
            return self.ros2.node.get_clock().now().to_msg()
        now = self.robot.time()
        whole = math.floor(now)
        return self._types[0](sec=whole, nanosec=min(int((now - whole) * 1e9), 999_999_999))

    def _publish(self, _changes: Mapping[str, object]) -> None:
        _, odometry, range_type, boolean, battery_type, clock_type = self._types
        state, stamp = self.robot.state, self._stamp()
        if self._clock is not None:
            self._clock.publish(clock_type(clock=stamp))
        odom = odometry()
        odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, "odom", "base_link"
        x, y, yaw = self.robot.world.odom_pose()
        odom.pose.pose.position.x, odom.pose.pose.position.y = x, y
        odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = (
            math.sin(yaw / 2),
            math.cos(yaw / 2),
        )
        odom.twist.twist.linear.x, odom.twist.twist.angular.z = state["v"], state["w"]
        self._odom.publish(odom)
        for key, publisher in self._ranges.items():
            reading, limit = state[key], self._ir[key]
            ray = range_type(radiation_type=range_type.INFRARED, min_range=0.0, max_range=limit)
            ray.header.stamp, ray.header.frame_id = stamp, key
            ray.range = math.inf if reading >= limit else reading
            publisher.publish(ray)
        for key, publisher in self._bools.items():
            publisher.publish(boolean(data=bool(state[key])))
        battery = battery_type(percentage=float(state["battery"]), present=True)
        battery.header.stamp = stamp
        battery.power_supply_status = (
            battery_type.POWER_SUPPLY_STATUS_CHARGING
            if state["docked"]
            else battery_type.POWER_SUPPLY_STATUS_DISCHARGING
        )
        self._battery.publish(battery)


def _ir_ranges(robot: SimRobot) -> dict[str, float]:
    """Each IR rangefinder's range (its MuJoCo ``cutoff``), read from the robot's model file."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(robot.world.model_path))
    ranges = {}
    for index in range(model.nsensor):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_SENSOR, index)
        if name in robot.world.state_keys and name.startswith("ir_"):
            ranges[name] = float(model.sensor_cutoff[index])
    return ranges


async def _serve(options: argparse.Namespace, out: TextIO) -> None:
    from pyrobots_aio.ros2 import attach_ros2
    from pyrobots_aio.sim import SimRobot

    robot = SimRobot(seed=options.seed, realtime=True, control_rate=options.control_rate)
    sim_clock = options.rate != 1.0
    ros2 = attach_ros2(
        robot,
        options.name,
        namespace=options.namespace,
        use_sim_time=sim_clock,
        health_keys=("v", "w", "bumper", "docked"),
    )
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    signals = (signal.SIGINT, signal.SIGTERM)
    for number in signals:
        loop.add_signal_handler(number, stop.set)
    try:
        async with robot:
            node = SimNode(robot, ros2, sim_clock=sim_clock, cmd_timeout=options.cmd_timeout)
            print(
                f"sim-node {ros2.full_name} ready (domain {ros2.domain_id}, x{options.rate:g} "
                f"real time): {len(node.topics)} topics under {ros2.namespace}",
                file=out,
                flush=True,
            )
            await stop.wait()
            node.close()
    finally:
        for number in signals:
            loop.remove_signal_handler(number)
    print(f"sim-node {ros2.full_name} stopped", file=out, flush=True)


def run_sim_node(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run ``sim-node`` until SIGINT or SIGTERM; return the exit code."""
    run_scaled(_serve, options, out, rate=options.rate)
    return 0
