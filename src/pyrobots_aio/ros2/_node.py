"""`Ros2Node`: a robot's ROS 2 side (``robot.ros2``), started and stopped with the robot.

`attach_ros2` gives any robot — a plain `Robot`, a `SimRobot`, a subclass —
its node, as the robot's extension ``ros2``: it starts inside ``async with
robot`` before the robot's own backend and stops after it, once every action
(ROS 2 goals included) is done. A `Ros2Robot`'s node is its backend's.
"""

from __future__ import annotations

import inspect
import logging
import math
from typing import TYPE_CHECKING, Any, TypeVar

from .._exceptions import PyRobotsError, Ros2Error
from ..actions import Action, ActionHandle
from ._calls import call_service, feedback_writer, run_goal
from ._diagnostics import Diagnostics
from ._rclpy import (
    check_message_type,
    check_namespace,
    check_node_name,
    check_topic,
    interface_of,
    qos_profile,
    rclpy_module,
    ros_name,
)
from ._serve import Ros2ActionServer, Ros2ServiceServer
from ._thread import RosThread
from ._topics import Ros2Publisher, Ros2Subscription, ToState, check_topic_type, state_mapping

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping

    from ..robot import Robot
    from ..supervision import HealthMonitor

_log = logging.getLogger("pyrobots_aio.ros2")

M = TypeVar("M")
S = TypeVar("S", Ros2ActionServer, Ros2ServiceServer)


def _positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < math.inf:
        msg = f"{name} must be a positive number of seconds, got {value!r}"
        raise ValueError(msg)
    return float(value)


def _strings(name: str, values: Iterable[str]) -> list[str]:
    given: object = values  # checked at run time: a lone string would be split into letters
    items = [] if isinstance(given, str) else list(values)
    if isinstance(given, str) or not all(isinstance(v, str) for v in items):
        msg = f"{name} must be a list of strings, such as ['-r', 'odom:=odometry'], got {values!r}"
        raise TypeError(msg)
    return items


class Ros2Node:
    """A robot's ROS 2 node: topics into ``robot.state``, publishers, services, goals.

    rclpy runs on a thread of its own with its own context (never rclpy's
    global one); everything it receives reaches the event loop through
    ``call_soon_threadsafe``, without polling. Give a robot its node with
    `attach_ros2`; the node lives inside ``async with robot``.

    ``ROS_DOMAIN_ID`` and ``ROS_AUTOMATIC_DISCOVERY_RANGE`` are read from the
    environment, as every ROS 2 process does; with neither the range nor
    ``ROS_LOCALHOST_ONLY`` set, discovery stays on this machine (``LOCALHOST``,
    where ROS 2 alone would use the subnet).

    Args:
        name: The node's name (``ros2 node list`` shows it).
        namespace: Its namespace (``/robot1``): relative topic names land under it.
        domain_id: The DDS domain; default: ``ROS_DOMAIN_ID`` (0 if unset).
        use_sim_time: Stamp messages with ``/clock``'s time rather than the system's
            (None: as ``ros_args`` say, ``-p use_sim_time:=true``).
        remap: Topic and service remappings, ``{"cmd_vel": "/other/cmd_vel"}``.
        ros_args: ROS arguments, as after ``--ros-args`` on a ROS 2 command line
            (``["-r", "odom:=odometry", "-p", "use_sim_time:=true"]``).
        standalone: The node is its process's own (a command, as ``sim-node``):
            it logs to ``/rosout`` and serves its parameters, and ``ros_args``
            set rcl's logging too (``--log-level``).
        diagnostics_period: Seconds between two ``/diagnostics`` messages (None: none).
        stale_after: Seconds after which a watched state key counts as stale.
        health_keys: State keys watched by ``/diagnostics`` besides those the
            subscriptions write.

    Raises:
        Ros2UnavailableError: rclpy cannot be imported.
        Ros2NameError: ROS 2 rejects the name or the namespace (its reason is quoted).

    Examples:
        >>> from pyrobots_aio import Robot
        >>> from pyrobots_aio.ros2 import attach_ros2
        >>> robot = Robot()
        >>> ros2 = attach_ros2(robot, "executive", namespace="robot1")  # doctest: +SKIP
        >>> ros2.full_name  # doctest: +SKIP
        '/robot1/executive'
    """

    def __init__(
        self,
        name: str = "pyrobots_aio",
        *,
        namespace: str = "/",
        domain_id: int | None = None,
        use_sim_time: bool | None = False,
        remap: Mapping[str, str] | None = None,
        ros_args: Iterable[str] = (),
        standalone: bool = False,
        diagnostics_period: float | None = 1.0,
        stale_after: float = 1.0,
        health_keys: Iterable[str] = (),
    ) -> None:
        rclpy_module()
        self.name = check_node_name(name)
        self.namespace = check_namespace(namespace)
        if domain_id is not None and (
            isinstance(domain_id, bool) or not isinstance(domain_id, int) or domain_id < 0
        ):
            msg = (
                f"domain_id must be a non-negative integer (None: ROS_DOMAIN_ID), got {domain_id!r}"
            )
            raise ValueError(msg)
        self._diagnostics_period = (
            None
            if diagnostics_period is None
            else _positive("diagnostics_period", diagnostics_period)
        )
        self._stale_after = _positive("stale_after", stale_after)
        self._health_keys = tuple(health_keys)
        remaps = [arg for old, new in (remap or {}).items() for arg in ("-r", f"{old}:={new}")]
        self._thread = RosThread(
            self.name,
            self.namespace,
            domain_id=domain_id,
            use_sim_time=None if use_sim_time is None else bool(use_sim_time),
            ros_args=[*remaps, *_strings("ros_args", ros_args)],
            citizen=standalone,
        )
        self._robot: Robot | None = None
        self._subscriptions: list[Ros2Subscription] = []
        self._publishers: list[Ros2Publisher[Any]] = []
        self._clients: dict[tuple[str, type], Any] = {}
        self._servers: list[Ros2ActionServer | Ros2ServiceServer] = []
        self._diagnostics: Diagnostics | None = None
        self._health: list[HealthMonitor] = []

    # -- facts --------------------------------------------------------------------

    @property
    def full_name(self) -> str:
        """The node's fully qualified name, ``/namespace/name``."""
        return f"{self.namespace.rstrip('/')}/{self.name}"

    @property
    def is_running(self) -> bool:
        """Whether the node is up (inside ``async with robot``)."""
        return self._robot is not None

    @property
    def node(self) -> Any:
        """The rclpy ``Node``, for what this bridge does not wrap.

        rclpy calls its callbacks on the ROS thread, not the event loop's:
        hand their results over with ``loop.call_soon_threadsafe``.
        """
        return self._running_thread().node

    @property
    def domain_id(self) -> int:
        """The DDS domain the node is in."""
        return int(self._running_thread().node.context.get_domain_id())

    def resolve(self, topic: str) -> str:
        """The full name of ``topic`` for this node: namespace and remapping applied.

        Raises:
            Ros2NameError: ROS 2 rejects the name (its reason is quoted).
        """
        return str(self._running_thread().node.resolve_topic_name(check_topic(topic)))

    # -- lifecycle (Backend) -------------------------------------------------------

    async def start(self, robot: Robot) -> None:
        """Bring the node up on its thread, then start ``/diagnostics``."""
        await self._thread.start()
        self._robot = robot
        if self._diagnostics_period is not None:
            self._diagnostics = Diagnostics(
                self._thread.node,
                robot,
                period=self._diagnostics_period,
                stale_after=self._stale_after,
                keys=self._watched_keys,
                monitors=self._health,
            )
            self._diagnostics.start()
        _log.info("ROS 2 node %s up (domain %d)", self.full_name, self.domain_id)

    async def stop(self) -> None:
        """Close everything, stop the thread, destroy the node and its context."""
        if self._diagnostics is not None:
            self._diagnostics.stop()
            self._diagnostics = None
        for sub in self._subscriptions:
            sub.close()
        for pub in self._publishers:
            pub.close()
        for server in self._servers:
            server.close()
        self._servers.clear()
        self._subscriptions.clear()
        self._publishers.clear()
        self._clients.clear()
        self._robot = None
        await self._thread.stop()

    # -- topics -------------------------------------------------------------------

    def publish_health(self, monitor: HealthMonitor) -> None:
        """Publish ``monitor``'s statuses on ``/diagnostics`` too, one per thing it watches.

        Each is a ``DiagnosticStatus`` named ``"<node>: <name>"`` at its level (OK, WARN,
        ERROR, STALE), with its message and last heartbeat; from the next publication on.

        Raises:
            TypeError: ``monitor`` is not a `HealthMonitor`.
            ValueError: The node publishes no diagnostics (``diagnostics_period=None``).
        """
        from ..supervision import HealthMonitor

        given: object = monitor  # checked at run time: the annotation promises nothing
        if not isinstance(given, HealthMonitor):
            msg = f"publish_health takes a HealthMonitor, got {given!r}"
            raise TypeError(msg)
        if self._diagnostics_period is None:
            msg = (
                f"{self!r} publishes no /diagnostics (diagnostics_period=None); "
                "give attach_ros2(..., diagnostics_period=1.0) to publish health"
            )
            raise ValueError(msg)
        if monitor not in self._health:
            self._health.append(monitor)

    def subscribe(
        self,
        topic: str,
        msg_type: type,
        to_state: ToState | None = None,
        *,
        callback: Callable[[Any], object] | None = None,
        qos: object = "default",
    ) -> Ros2Subscription:
        """Write each message on ``topic`` into ``robot.state`` (and/or call ``callback``).

        ``to_state`` is a state key (the whole message is written under it), a
        map ``{state_key: "field.path"}`` (checked against ``msg_type`` now), or
        a plain function of the message returning ``{key: value}``. Each message
        is written as one batch, so monitors see every message.

        Args:
            topic: The topic (relative names land in the node's namespace).
            msg_type: The message class, e.g. ``nav_msgs.msg.Odometry``.
            to_state: How messages become state (see above).
            callback: A plain function called with each message, on the loop.
            qos: A history depth, a profile name (``"default"``,
                ``"sensor_data"``: best effort, for sensor streams) or a profile.

        Raises:
            TopicTypeError: The topic is known to carry another type (both named).
            Ros2NameError: ROS 2 rejects the topic name.

        Examples:
            >>> sub = robot.ros2.subscribe(  # doctest: +SKIP
            ...     "odom", Odometry, {"x": "pose.pose.position.x", "v": "twist.twist.linear.x"}
            ... )
        """
        thread = self._running_thread()
        msg_type = check_message_type(msg_type)
        if to_state is None and callback is None:
            msg = f"subscribing to {topic!r} needs to_state=..., callback=..., or both"
            raise TypeError(msg)
        if callback is not None and (
            inspect.iscoroutinefunction(callback) or not callable(callback)
        ):
            msg = f"callback must be a plain function of the message, got {callback!r}"
            raise TypeError(msg)
        mapping = None if to_state is None else state_mapping(msg_type, to_state)
        profile = qos_profile(qos)
        full = self.resolve(topic)
        check_topic_type(thread.node, full, msg_type, "subscribe to")
        assert self._robot is not None  # running
        sub = Ros2Subscription(
            thread, self._robot, full, msg_type, mapping=mapping, callback=callback, qos=profile
        )
        self._subscriptions.append(sub)
        return sub

    def publisher(
        self, topic: str, msg_type: type[M], *, qos: object = "default"
    ) -> Ros2Publisher[M]:
        """A publisher of ``msg_type`` on ``topic``; its ``publish`` never blocks.

        Raises:
            TopicTypeError: The topic is known to carry another type (both named).
            Ros2NameError: ROS 2 rejects the topic name.

        Examples:
            >>> cmd_vel = robot.ros2.publisher("cmd_vel", Twist)  # doctest: +SKIP
            >>> cmd_vel.publish(Twist())  # doctest: +SKIP
        """
        thread = self._running_thread()
        check_message_type(msg_type)
        profile = qos_profile(qos)
        full = self.resolve(topic)
        check_topic_type(thread.node, full, msg_type, "publish on")
        pub = Ros2Publisher(thread, full, msg_type, profile)
        self._publishers.append(pub)
        return pub

    # -- services and goals -------------------------------------------------------

    async def call(self, service: str, request: Any, *, srv_type: type | None = None) -> Any:
        """Call ``service`` with ``request`` and return the response.

        Waits for the server to appear first. Cancellable: a cancelled call
        drops its request (callers own deadlines: ``asyncio.timeout``).

        Examples:
            >>> response = await robot.ros2.call("reset", Trigger.Request())  # doctest: +SKIP
        """
        thread = self._running_thread()
        srv_type = srv_type or interface_of(request, "Request", "service")
        if not isinstance(request, srv_type.Request):  # type: ignore[attr-defined]
            msg = f"{service!r} takes a {ros_name(srv_type)} request, got {request!r}"
            raise TypeError(msg)
        full, client = self._client(service, srv_type)
        return await call_service(thread, client, full, request)

    def goal(
        self,
        action_name: str,
        goal: Any,
        *,
        action_type: type | None = None,
        feedback_to_state: ToState | None = None,
    ) -> ActionHandle[Any]:
        """Send ``goal`` to the ROS 2 action server ``action_name``, as a pyrobots_aio action.

        The returned handle's result is the goal's result. Cancelling the
        action cancels the goal and waits (within ``cancel_grace``) for the
        server's answer; each feedback is written to ``robot.state`` through
        ``feedback_to_state`` (same forms as `subscribe`'s ``to_state``).
        A rejected goal fails with `GoalRejectedError`; an aborted one (or one
        cancelled by someone else) with `GoalError`.

        Examples:
            >>> handle = robot.ros2.goal("fibonacci", Fibonacci.Goal(order=5))  # doctest: +SKIP
            >>> (await handle).sequence  # doctest: +SKIP
            array('i', [0, 1, 1, 2, 3, 5])
        """
        thread = self._running_thread()
        action_type = action_type or interface_of(goal, "Goal", "action")
        if not isinstance(goal, action_type.Goal):  # type: ignore[attr-defined]
            msg = f"{action_name!r} takes a {ros_name(action_type)} goal, got {goal!r}"
            raise TypeError(msg)
        mapping = (
            None
            if feedback_to_state is None
            else state_mapping(action_type.Feedback, feedback_to_state)  # type: ignore[attr-defined]
        )
        full, client = self._client(action_name, action_type)
        assert self._robot is not None  # running
        act: Action[Robot, Any, Any] = Action(run_goal)
        act.name = f"goal {full}"
        feedback = feedback_writer(thread, self._robot, mapping)
        return act(self._robot, thread, client, action_name=full, goal=goal, feedback=feedback)

    async def wait_for_server(self, name: str, interface: type) -> None:
        """Return once the service or action server ``name`` of type ``interface`` is up.

        `call` and `goal` wait for their server anyway; this lets a program
        wait beforehand (under its own deadline), e.g. at start-up.

        Examples:
            >>> async with asyncio.timeout(10):  # doctest: +SKIP
            ...     await robot.ros2.wait_for_server("fibonacci", Fibonacci)
        """
        thread = self._running_thread()
        _, client = self._client(name, interface)
        is_action = hasattr(interface, "Goal")
        await thread.wait_until(client.server_is_ready if is_action else client.service_is_ready)

    def serve_action(
        self, name: str, action_type: type, fn: Callable[..., Any]
    ) -> Ros2ActionServer:
        """Serve the ROS 2 action ``name``: each goal runs ``fn`` as a pyrobots_aio action.

        ``fn`` is an ``async def`` (or an `action`, with its locks) called as
        ``fn(robot, goal, feedback)``; ``feedback(**fields)`` (or
        ``feedback(Feedback(...))``) publishes the goal's feedback; its return
        value (an ``action_type.Result``, or None for an empty one) is the
        goal's result. Resources, priorities, pause and the emergency stop
        apply to it as to any action. A goal that cannot run (the emergency
        stop is latched, a ``wait=False`` resource is busy, the action fails at
        its first step) is rejected: its client sees only that it was not
        accepted (ROS 2's action protocol has no field for the reason), and
        the reason is logged (a WARNING on the ``pyrobots_aio.ros2`` logger).
        A ROS 2 cancel arrives in the action as ``ActionCancelled``: its
        cleanup runs, and the goal ends CANCELED; cancelled by anything else,
        or failed, it ends ABORTED with an empty result (the reason logged).
        The emergency stop ends every goal running, holding resources or not
        (ABORTED). A paused goal stays active for its client (no ROS 2 status
        says paused) and sends no feedback until it resumes.

        Example:
            >>> async def count(robot, goal, feedback):  # doctest: +SKIP
            ...     for i in range(goal.order):
            ...         feedback(sequence=list(range(i + 1)))
            ...         await robot.sleep(0.1)
            ...     return Fibonacci.Result(sequence=list(range(goal.order)))
            >>> robot.ros2.serve_action("count", Fibonacci, count)  # doctest: +SKIP
        """
        return self._serve(Ros2ActionServer, name, action_type, fn)

    def serve_service(self, name: str, srv_type: type, fn: Callable[..., Any]) -> Ros2ServiceServer:
        """Serve the ROS 2 service ``name``: each request runs ``fn(robot, request)`` as an action.

        Its return value (a ``srv_type.Response``) is the response, sent once
        the action is done. ROS 2 services cannot refuse a request: one whose
        action cannot run (the emergency stop latched, a ``wait=False``
        resource busy), fails or is cancelled (the emergency stop ends the
        requests running) is answered ``success=False`` with the reason in
        ``message`` where the response type has those fields (std_srvs'
        Trigger and SetBool, and the many types like them), else with an
        empty response, which its client cannot tell from a real one. The
        reason is logged either way (a WARNING on ``pyrobots_aio.ros2``).

        Example:
            >>> async def reset(robot, request):  # doctest: +SKIP
            ...     await robot.stop()
            ...     return Trigger.Response(success=True)
            >>> robot.ros2.serve_service("reset", Trigger, reset)  # doctest: +SKIP
        """
        return self._serve(Ros2ServiceServer, name, srv_type, fn)

    # -- internals ----------------------------------------------------------------

    def _client(self, name: str, interface: type) -> tuple[str, Any]:
        """The full name and the (one, cached) client of service or action ``name``."""
        node = self._running_thread().node
        is_action = hasattr(interface, "Goal")
        if not (is_action or hasattr(interface, "Request")):
            msg = f"{interface!r} is not a ROS 2 service or action type"
            raise TypeError(msg)
        kind = "action name" if is_action else "service name"
        full = str(node.resolve_service_name(check_topic(name, kind)))
        client = self._clients.get((full, interface))
        if client is None:
            if is_action:
                client = rclpy_module("rclpy.action").ActionClient(node, interface, full)
            else:
                client = node.create_client(interface, full)
            self._clients[full, interface] = client
        return full, client

    def _running_thread(self) -> RosThread:
        if self._robot is None:
            msg = (
                f"the ROS 2 node {self.name!r} is not running; use it inside 'async with robot:' "
                "(attach it with attach_ros2(robot) first)"
            )
            raise Ros2Error(msg)
        return self._thread

    def _serve(self, kind: type[S], name: str, interface: type, fn: Callable[..., Any]) -> S:
        thread = self._running_thread()
        assert self._robot is not None  # running
        full = str(thread.node.resolve_service_name(check_topic(name, f"{kind.kind} name")))
        server = kind(self._robot, thread, full, interface, fn)
        self._servers.append(server)
        return server

    def _watched_keys(self) -> set[str]:
        keys = set(self._health_keys)
        for sub in self._subscriptions:
            keys |= sub.keys
        return keys

    def __repr__(self) -> str:
        state = "running" if self.is_running else "stopped"
        return f"<Ros2Node {self.full_name} {state}>"


def attach_ros2(robot: Robot, name: str = "pyrobots_aio", **options: Any) -> Ros2Node:
    """Give ``robot`` a ROS 2 node, as ``robot.ros2``; it runs inside ``async with robot``.

    The node is the robot's extension ``ros2`` (`Robot.add_extension`): it
    starts before the robot's backend and stops after it, once every action
    (ROS 2 goals included) is done.

    Args:
        robot: Any robot, not running yet.
        name: The node's name.
        **options: `Ros2Node` options (``namespace``, ``domain_id``, ``use_sim_time`` ...).

    Returns:
        The node (also ``robot.ros2``).

    Raises:
        PyRobotsError: The robot is running, or has a ROS 2 node already.

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot
        >>> from std_msgs.msg import Float64  # doctest: +SKIP
        >>> async def main() -> None:
        ...     robot = Robot()
        ...     attach_ros2(robot, "executive", namespace="/robot1")
        ...     async with robot:
        ...         robot.ros2.subscribe("battery", Float64, {"battery": "data"})
        >>> asyncio.run(main())  # doctest: +SKIP
    """
    if robot.is_running:
        msg = f"attach the ROS 2 node before 'async with robot:', not while {robot!r} runs"
        raise PyRobotsError(msg)
    existing = getattr(robot, "ros2", None)
    if isinstance(existing, Ros2Node):
        msg = f"{robot!r} has a ROS 2 node already: {existing!r}"
        raise PyRobotsError(msg)
    node = Ros2Node(name, **options)
    robot.add_extension("ros2", node)
    return node
