"""``pyrobots-aio sim-node``: the simulated robot as a ROS 2 node.

A `SimRobot` (real time, or ``--rate`` times faster) with a ROS 2 node
(`pyrobots_aio.ros2.attach_ros2`) that publishes its sensors every control
tick and drives it from ``cmd_vel``, through a ROS 2 profile
(``--profile``, `pyrobots_aio.ros2.Profile`: the table `Ros2Robot` reads
through too); any ROS 2 tool sees it, and a robot in another process (or
on another machine) can drive it. Topic names are relative, so
``--namespace /robot1`` puts them under ``/robot1``; several nodes run side
by side under different namespaces. ``--robots N`` puts N robots in one
world, each with its node under ``<namespace>/robotK`` (`_sim_robots`).
Ctrl-C (SIGINT) or SIGTERM stops it cleanly (exit code 0). The ``standard``
profile's topics:

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
``tf``                        tf2_msgs/msg/TFMessage        reliable, 100
``tf_static``                 tf2_msgs/msg/TFMessage        reliable, transient local
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
- ``tf``: ``odom -> base_link`` each control tick, the odometry's pose and
  stamp; ``tf_static``: ``base_link -> <sensor>`` once (latched) for each
  frame on the robot's body (``ir_<position>``, ``cliff_<position>``,
  ``bumper_left``/``_right``, ``imu``, ``charge_contacts``). Relative names:
  ``/tf`` at the root namespace, ``<namespace>/tf`` under one (as a namespaced
  Create 3 has them). Needs ``tf2_msgs`` (``pyrobots-aio ros2 interfaces build``).
- ``--ros-args ...`` (last on the line): remapping, ``-p use_sim_time:=true``
  (stamps and ``/clock`` then simulated, from 0), ``--log-level``. The options
  are served as read-only parameters; the log goes to ``/rosout`` too. A
  command that is not finite stops the wheels; a burst of them is logged once
  at its start and once, with the count, at its end.
- Stamps: the system clock in real time; the simulation's clock (which
  ``/clock`` carries, from 0) when ``--rate`` is not 1. Either says when the
  world was as published: a node held up (a busy machine) catches up tick by
  tick, each stamped with the time it simulates, not the moment it is sent.

``--profile create3`` speaks the iRobot Create 3's interface instead
(`pyrobots_aio.ros2.CREATE3`: ``hazard_detection``, ``ir_intensity``,
``dock_status``, ``odom``, ``cmd_vel``, ``battery_state``) and serves its
action servers ``undock``, ``dock``, ``drive_distance``, ``rotate_angle`` and
``navigate_to_position`` over the simulated robot's own motion actions
(``pyrobots_aio.ros2.serve_create3``), so a Create 3 program runs against it.
A motion that pushes for ``--stall-timeout`` simulated seconds (1.5) without
progress fails (`StallError`), and its goal is aborted, as a base's firmware
gives up.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import math
import signal
from typing import TYPE_CHECKING, Any, TextIO, TypeVar

from pyrobots_aio.loops import run_scaled
from pyrobots_aio.motion import STALL_TIMEOUT
from pyrobots_aio.ros2 import CREATE3, PROFILES, STANDARD, Odometry, serve_create3

from ._bursts import Refusals
from ._citizen import RosoutHandler, declare_options, uses_sim_time
from ._sim_robots import add_robots_argument, sim_robots, topics_line

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Mapping

    import numpy as np
    from numpy.typing import NDArray

    from pyrobots_aio.ros2 import Profile, Ros2Node, Ros2Publisher, TfBroadcaster, Topic
    from pyrobots_aio.sim import SimRobot

V = TypeVar("V")
_log = logging.getLogger("pyrobots_aio.cli")


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
        "bumper, cliff and dock state out (docs/guides/ros2.md lists the topics). "
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
    node.add_argument(
        "--stall-timeout",
        type=positive,
        default=STALL_TIMEOUT,
        metavar="SECONDS",
        help="simulated seconds a motion may push without progress before it fails, as a "
        f"base's firmware gives up (default: {STALL_TIMEOUT:g})",
    )
    node.add_argument("--seed", type=int, default=0, help="seeds the IR noise (default: 0)")
    node.add_argument(
        "--profile",
        choices=sorted(PROFILES),
        default=STANDARD.name,
        help="the ROS 2 topics, types and conversions, as Ros2Robot(profile=...) takes them "
        "(default: standard)",
    )
    node.add_argument(
        "--ros-args",
        nargs=argparse.REMAINDER,
        default=[],
        metavar="ARG",
        help="ROS arguments, as every ROS 2 node takes them, to the end of the line: "
        "-r from:=to (remapping), -p use_sim_time:=true, --log-level debug ...",
    )
    add_robots_argument(node)
    node.set_defaults(command=run_sim_node)


class SimNode:
    """The ROS 2 face of a running simulated robot: a profile's topics out each tick, command in.

    Args:
        robot: The running simulated robot.
        ros2: Its node.
        profile: The topics, types and conversions (those `Ros2Robot` reads).
        sim_clock: Stamp with the simulation's clock and publish ``/clock``.
        clock_origin: The robot's time that is 0 on ``/clock``.
        cmd_timeout: Seconds a command holds before the wheels stop.
        publish_clock: Whether this node publishes ``/clock`` (with ``sim_clock``):
            in a world of several robots, only the first's does.
    """

    def __init__(
        self,
        robot: SimRobot,
        ros2: Ros2Node,
        *,
        profile: Profile,
        sim_clock: bool,
        clock_origin: float = 0.0,
        cmd_timeout: float,
        publish_clock: bool = True,
    ):
        from builtin_interfaces.msg import Time
        from rclpy.duration import Duration
        from rosgraph_msgs.msg import Clock

        self._time, self._clock_type, self._duration = Time, Clock, Duration
        self.robot, self.ros2, self.profile = robot, ros2, profile
        self._cmd_timeout = cmd_timeout
        self._stop_timer: asyncio.TimerHandle | None = None
        odometry, command = profile.odometry, profile.command
        self._refused = Refusals(ros2.resolve(command.name))
        self._odom = self._publisher(odometry)
        self._sensors = [self._publisher(t) for t in profile.sensors(robot.sensors)]
        self._status = [self._publisher(t) for t in profile.status]
        self._clock = ros2.publisher("/clock", Clock) if sim_clock and publish_clock else None
        self._sim_clock, self._clock_origin = sim_clock, clock_origin
        self._command = command.message_class()
        self._cmd = ros2.subscribe(
            command.name, self._command, callback=self._on_command, qos=command.qos
        )
        self._tf = _tf_broadcaster(ros2)
        if self._tf is not None:
            self._tf.send_static(_sensor_frames(robot), self._stamp())
        self._state = robot.state.subscribe(self._publish, keys=robot.world.state_keys)
        self.topics = sorted(p.topic for _, _, p in (self._odom, *self._sensors))

    def _publisher(self, topic: Topic[V]) -> tuple[Topic[V], type, Ros2Publisher[Any]]:
        cls = topic.message_class()
        return topic, cls, self.ros2.publisher(topic.name, cls, qos=topic.qos)

    def close(self) -> None:
        """Stop publishing and listening (the robot's shutdown closes the ROS side)."""
        self._state.close()
        self._refused.close()
        if self._stop_timer is not None:
            self._stop_timer.cancel()

    def _on_command(self, message: Any) -> None:
        v, w = self.profile.command.decode(message)
        if not (math.isfinite(v) and math.isfinite(w)):
            self.robot.stop()
            self._refused.refuse(f"refused a command that is not finite ({v!r}, {w!r}): stopped")
            return
        self.robot.drive(v, w)
        if self._stop_timer is not None:
            self._stop_timer.cancel()
        self._stop_timer = asyncio.get_running_loop().call_later(self._cmd_timeout, self.robot.stop)

    def _stamp(self) -> Any:
        """When the world was as published: a tick that runs late (catching up) is not now."""
        world = self.robot.world.time
        if not self._sim_clock:
            late = self._duration(nanoseconds=round((self.robot.time() - world) * 1e9))
            return (self.ros2.node.get_clock().now() - late).to_msg()
        now = world - self._clock_origin
        whole = math.floor(now)
        return self._time(sec=whole, nanosec=min(int((now - whole) * 1e9), 999_999_999))

    def _publish(self, _changes: Mapping[str, object]) -> None:
        state, stamp = self.robot.state, self._stamp()
        if self._clock is not None:
            self._clock.publish(self._clock_type(clock=stamp))
        odometry, odometry_type, odom = self._odom
        reading = Odometry(self.robot.world.odom_pose(), state["v"], state["w"])
        odom.publish(odometry.encode(odometry_type, reading, stamp))
        if self._tf is not None:
            self._tf.send_odometry(reading.pose, stamp)
        for topic, cls, publisher in (*self._sensors, *self._status):
            publisher.publish(topic.encode(cls, state, stamp))


def _tf_broadcaster(ros2: Ros2Node) -> TfBroadcaster | None:
    """The tf broadcaster, or None (said once) when tf2_msgs is not built."""
    from pyrobots_aio.ros2 import TfBroadcaster, tf_available

    if tf_available():
        return TfBroadcaster(ros2)
    _log.warning(
        "sim-node publishes no tf: tf2_msgs cannot be imported "
        "(build it with: pyrobots-aio ros2 interfaces build tf2_msgs)"
    )
    return None


def _sensor_frames(robot: SimRobot) -> list[tuple[str, str, NDArray[np.float64]]]:
    """``base_link -> frame`` for each frame on the robot's body (its sensors), as it stands."""
    world = {"odom", "base_link", "dock"}
    return [
        ("base_link", frame, robot.poses.inframe(frame, "base_link").matrix())
        for frame in robot.world.frame_names
        if frame not in world
    ]


async def _serve(options: argparse.Namespace, out: TextIO) -> None:
    from pyrobots_aio.ros2 import attach_ros2, profile_named

    profile = profile_named(options.profile)
    faster = options.rate != 1.0
    robots = [
        (
            robot,
            attach_ros2(
                robot,
                options.name,
                namespace=namespace,
                use_sim_time=True if faster else None,  # at real time, as --ros-args say
                ros_args=options.ros_args,
                standalone=True,
                health_keys=("v", "w", "bumper", "docked"),
            ),
        )
        for robot, namespace in sim_robots(options)
    ]
    first = robots[0][1]
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    signals = (signal.SIGINT, signal.SIGTERM)
    for number in signals:
        loop.add_signal_handler(number, stop.set)
    try:
        async with contextlib.AsyncExitStack() as running:
            for robot, _ in robots:
                await running.enter_async_context(robot)
            await running.enter_async_context(_rosout(first))  # the process's log, once
            # A faster loop's clock starts at 0; the real-time one's is the machine's.
            origin = 0.0 if faster else robots[0][0].time()
            nodes = [
                _start_node(robot, ros2, options, profile, origin, publish_clock=ros2 is first)
                for robot, ros2 in robots
            ]
            # As --ros-args may have remapped them:
            name = ", ".join(ros2.node.get_fully_qualified_name() for _, ros2 in robots)
            topics = topics_line(
                len(nodes[0].topics), [ros2.node.get_namespace() for _, ros2 in robots]
            )
            print(
                f"sim-node {name} ready (domain {first.domain_id}, x{options.rate:g} "
                f"real time): {topics}",
                file=out,
                flush=True,
            )
            await stop.wait()
            for node in nodes:
                node.close()
    finally:
        for number in signals:
            loop.remove_signal_handler(number)
    print(f"sim-node {name} stopped", file=out, flush=True)


def _start_node(
    robot: SimRobot,
    ros2: Ros2Node,
    options: argparse.Namespace,
    profile: Profile,
    clock_origin: float,
    *,
    publish_clock: bool,
) -> SimNode:
    """One running robot's ROS 2 face: its parameters, topics, and a profile's servers."""
    declare_options(ros2.node, options)
    node = SimNode(
        robot,
        ros2,
        profile=profile,
        sim_clock=options.rate != 1.0 or uses_sim_time(ros2.node),
        clock_origin=clock_origin,
        cmd_timeout=options.cmd_timeout,
        publish_clock=publish_clock,
    )
    if profile is CREATE3:
        serve_create3(robot, ros2)
    return node


@contextlib.asynccontextmanager
async def _rosout(ros2: Ros2Node) -> AsyncIterator[None]:
    """The process's log records on ``/rosout`` too, while the node runs."""
    handler = RosoutHandler(ros2.node.get_logger())
    logging.getLogger().addHandler(handler)
    try:
        yield
    finally:
        logging.getLogger().removeHandler(handler)


def run_sim_node(options: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    """Run ``sim-node`` until SIGINT or SIGTERM; return the exit code."""
    run_scaled(_serve, options, out, rate=options.rate)
    return 0
