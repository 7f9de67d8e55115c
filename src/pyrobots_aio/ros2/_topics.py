"""Topics: subscriptions that write ``robot.state``, and publishers.

A message reaches the loop without polling: DDS rings the subscription's
doorbell and the loop takes the message itself, or, where that cannot be
done, the node's receiver thread takes it and hands it over (see
`_receiver`). Each message is written to the state as one batch, in order.
At most the QoS history depth waits for the loop: if the loop falls that far
behind, the oldest messages are dropped (and counted), as a ROS 2
``KEEP_LAST`` queue would.
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import operator
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from .._exceptions import QosMismatchError, Ros2Error, TopicTypeError
from ._doorbell import DoorbellUnavailable
from ._rclpy import rclpy_module, ros_name
from ._receiver import LoopFeed, ThreadFeed, taken_elsewhere

if TYPE_CHECKING:
    from ..robot import Robot
    from ._thread import RosThread

_log = logging.getLogger("pyrobots_aio.ros2")

M = TypeVar("M")

ToState = str | Mapping[str, str] | Callable[[Any], Mapping[str, object] | None]
"""How a message becomes state: a key (whole message), ``{key: "field.path"}``, or a function."""


def _fields(message: object) -> list[str]:
    describe = getattr(type(message), "get_fields_and_field_types", None)
    return sorted(describe()) if describe is not None else []


def _check_path(msg_type: type, path: object) -> Callable[[Any], object]:
    if not isinstance(path, str) or not path:
        msg = f"a field path must be a dotted string such as 'pose.pose.position.x', got {path!r}"
        raise TypeError(msg)
    value: object = msg_type()
    for depth, part in enumerate(path.split(".")):
        fields = _fields(value)
        if part not in fields:
            where = ".".join(path.split(".")[:depth]) or ros_name(msg_type)
            msg = f"{ros_name(msg_type)} has no field {path!r}: {where} has fields {fields}"
            raise ValueError(msg)
        value = getattr(value, part)
    return operator.attrgetter(path)


def state_mapping(
    msg_type: type, to_state: ToState
) -> Callable[[Any], Mapping[str, object] | None]:
    """A function from a message to the state values it writes; field paths checked now.

    Raises:
        ValueError: A field path names no field of ``msg_type``.
        TypeError: ``to_state`` is none of the three forms.
    """
    if isinstance(to_state, str):
        key = to_state
        return lambda message: {key: message}
    if isinstance(to_state, Mapping):
        getters = {key: _check_path(msg_type, path) for key, path in to_state.items()}
        if not getters or not all(isinstance(key, str) for key in getters):
            msg = f"a field map needs state keys (strings) mapped to field paths, got {to_state!r}"
            raise TypeError(msg)
        return lambda message: {key: get(message) for key, get in getters.items()}
    if callable(to_state) and not inspect.iscoroutinefunction(to_state):
        return to_state
    msg = (
        "to_state must be a state key, a {state_key: 'field.path'} map or a plain function "
        f"of the message returning {{key: value}}, got {to_state!r}"
    )
    raise TypeError(msg)


def check_topic_type(node: Any, topic: str, msg_type: type, verb: str) -> None:
    """Raise `TopicTypeError` if the ROS graph already shows ``topic`` with another type."""
    ours = ros_name(msg_type)
    for name, types in node.get_topic_names_and_types():
        theirs = [t for t in types if t != ours]
        if name == topic and theirs:
            msg = (
                f"cannot {verb} {topic!r} as {ours}: the topic carries {', '.join(theirs)}; "
                f"use that type, or another topic"
            )
            raise TopicTypeError(msg)


class Matches:
    """How many endpoints match a publisher or subscription; waitable (fed by DDS events)."""

    def __init__(self) -> None:
        self.count = 0
        self._waiters: list[tuple[int, asyncio.Future[int]]] = []

    def update(self, count: int) -> None:
        """Record the current count (on the loop) and wake the waiters it satisfies."""
        self.count = count
        for wanted, future in list(self._waiters):
            if count >= wanted and not future.done():
                future.set_result(count)

    async def wait(self, wanted: int) -> int:
        """Return the count once at least ``wanted`` endpoints match."""
        if isinstance(wanted, bool) or not isinstance(wanted, int) or wanted < 1:
            msg = f"the number of endpoints to wait for must be a positive integer, got {wanted!r}"
            raise ValueError(msg)
        if self.count >= wanted:
            return self.count
        future: asyncio.Future[int] = asyncio.get_running_loop().create_future()
        entry = (wanted, future)
        self._waiters.append(entry)
        try:
            return await future
        finally:
            self._waiters.remove(entry)

    def fail(self, error: Exception) -> None:
        """Fail every waiter (the node stopped)."""
        for _, future in self._waiters:
            if not future.done():
                future.set_exception(error)


def describe_qos(qos: Any) -> str:
    """The policies that decide whether two ends match: ``reliable, volatile, keep last 10``."""

    def named(policy: Any) -> str:
        return str(policy.name).lower().replace("_", " ")

    policies = [named(qos.reliability), named(qos.durability)]
    if named(qos.history) == "keep last":  # (the graph does not tell a peer's history)
        policies.append(f"keep last {qos.depth}")
    return ", ".join(policies)


def _node_of(endpoint: Any) -> str:
    """The node of a graph endpoint, ``/namespace/name``; its names come after its QoS."""
    if endpoint.node_name.startswith("_NODE_NAME_UNKNOWN"):
        return "a node not named in the graph yet"
    return f"{endpoint.node_namespace.rstrip('/')}/{endpoint.node_name}"


_FIXES = {
    "RELIABILITY": "a best-effort publisher needs a best-effort subscription (qos='sensor_data')",
    "DURABILITY": "a transient-local subscription needs a transient-local publisher",
}


class _Endpoint:
    """What a subscription and a publisher share: names, matches, closing, QoS mismatches.

    Attributes:
        error: The `QosMismatchError` of the last peer whose QoS cannot match, or None.
    """

    _role, _peer = "publisher", "subscription"

    def __init__(self, thread: RosThread, topic: str, msg_type: type, qos: Any) -> None:
        self.topic, self.msg_type, self.qos = topic, msg_type, qos
        self.matches = Matches()
        self.error: QosMismatchError | None = None
        self._thread = thread
        self._closed = False

    def _events(self, kind: str) -> Any:
        callbacks = getattr(rclpy_module("rclpy.event_handler"), kind)
        return callbacks(matched=self._on_matched, incompatible_qos=self._on_incompatible)

    def _on_matched(self, info: Any) -> None:  # on the ROS thread or the receiver
        self._thread.to_loop(self.matches.update, info.current_count)

    def _on_incompatible(self, info: Any) -> None:  # on the ROS thread or the receiver
        policy = str(info.last_policy_kind.name).removeprefix("RMW_QOS_POLICY_")
        error = QosMismatchError(self._mismatch(policy))
        self._thread.to_loop(self._mismatched, error)

    def _mismatch(self, policy: str) -> str:
        """Both profiles named: ours, and each peer's the graph shows that cannot match it."""
        qos = rclpy_module("rclpy.qos")
        node = self._thread.node
        peers = (
            node.get_subscriptions_info_by_topic(self.topic)
            if self._role == "publisher"
            else node.get_publishers_info_by_topic(self.topic)
        )
        ours = self.qos

        def clashes(peer: Any) -> bool:
            pair = (
                (ours, peer.qos_profile) if self._role == "publisher" else (peer.qos_profile, ours)
            )
            return bool(qos.qos_check_compatible(*pair)[0] == qos.QoSCompatibility.ERROR)

        theirs = [
            f"{_node_of(peer)} ({describe_qos(peer.qos_profile)})"
            for peer in peers
            if clashes(peer)
        ] or ["a node the graph does not list yet"]
        fix = _FIXES.get(policy, f"make the {policy.lower()} policies compatible")
        return (
            f"QoS mismatch on {self.topic}: this {self._role} ({describe_qos(ours)}) and the "
            f"{self._peer} of {', '.join(theirs)} are incompatible in {policy}, so no message "
            f"passes between them; {fix}"
        )

    def _mismatched(self, error: QosMismatchError) -> None:  # on the loop
        if self._closed or (self.error is not None and str(self.error) == str(error)):
            return
        self.error = error
        _log.error("%s", error)
        self._fail_waiters(error)

    def _fail_waiters(self, error: Exception) -> None:
        self.matches.fail(error)

    async def _matched(self, count: int) -> int:
        if self.error is not None:
            raise self.error
        return await self.matches.wait(count)

    def _close(self, destroy: str, entity: Any, what: str) -> Ros2Error | None:
        """Destroy ``entity`` (``node.<destroy>(entity)``); the error waiters get, or None."""
        if self._closed:
            return None
        self._closed = True
        node = self._thread.node
        if node is not None:
            getattr(node, destroy)(entity)
        return Ros2Error(f"the {what} {self.topic!r} is closed")


class Ros2Subscription(_Endpoint):
    """A topic feeding ``robot.state`` (made by `Ros2Node.subscribe`).

    A publisher whose QoS cannot match it (a best-effort publisher, a reliable
    subscription) is an error, logged once and kept as `error`: the waits of
    this subscription raise it (`QosMismatchError`, both profiles named).

    Attributes:
        topic: The topic's full name (namespace and remapping applied).
        msg_type: The message class.
        received: Messages delivered to the state (or the callback) so far.
        dropped: Messages dropped because the event loop fell a whole queue behind.
        keys: The state keys this subscription has written.
        error: The `QosMismatchError` of a publisher that cannot match, or None.
    """

    _role, _peer = "subscription", "publisher"

    def __init__(
        self,
        thread: RosThread,
        robot: Robot,
        topic: str,
        msg_type: type,
        *,
        mapping: Callable[[Any], Mapping[str, object] | None] | None,
        callback: Callable[[Any], object] | None,
        qos: Any,
    ) -> None:
        super().__init__(thread, topic, msg_type, qos)
        self.received = 0
        self.keys: set[str] = set()
        self._robot = robot
        self._mapping, self._callback = mapping, callback
        self._next: list[asyncio.Future[Any]] = []
        self._sub, self._feed = self._subscribe(max(1, qos.depth))

    def _subscribe(self, depth: int) -> tuple[Any, LoopFeed | ThreadFeed]:
        """The rclpy subscription, and its feed: rung on the loop if it can, else a thread's."""
        thread, receiver = self._thread, self._thread.receiver
        node, events = thread.node, rclpy_module("rclpy.event_handler")
        if receiver.doorbells:
            kinds = events.QoSSubscriptionEventType
            quiet = events.SubscriptionEventCallbacks(use_default_callbacks=False)
            sub = node.create_subscription(
                self.msg_type,
                self.topic,
                taken_elsewhere,
                self.qos,
                event_callbacks=quiet,
                callback_group=receiver.group,
            )
            rung = {
                kinds.RCL_SUBSCRIPTION_MATCHED: self._on_matched,
                kinds.RCL_SUBSCRIPTION_REQUESTED_INCOMPATIBLE_QOS: self._on_incompatible,
            }
            try:
                return sub, LoopFeed(thread.loop, sub, depth, self._deliver, rung)
            except DoorbellUnavailable as why:
                _log.info("ROS 2 messages reach the loop through a thread: %s", why)
                receiver.doorbells = False
                node.destroy_subscription(sub)
        sub = node.create_subscription(
            self.msg_type,
            self.topic,
            taken_elsewhere,
            self.qos,
            event_callbacks=self._events("SubscriptionEventCallbacks"),
            callback_group=receiver.group,
        )
        return sub, ThreadFeed(receiver, sub, depth, thread.to_loop, self._deliver)

    @property
    def publishers(self) -> int:
        """How many publishers this subscription is matched with now."""
        return self.matches.count

    @property
    def queued(self) -> int:
        """Messages received from DDS and not yet delivered on the loop (the loop's lag)."""
        return self._feed.queued

    @property
    def dropped(self) -> int:
        """Messages dropped because the event loop fell a whole queue behind."""
        return self._feed.dropped

    async def wait_for_publishers(self, count: int = 1) -> int:
        """Return once at least ``count`` publishers are matched (wrap it in a timeout).

        Raises:
            QosMismatchError: One of the topic's publishers cannot match this QoS.
        """
        return await self._matched(count)

    async def wait_for_message(self) -> Any:
        """Return the next message delivered (once it is in the state).

        Raises:
            QosMismatchError: A publisher of the topic cannot match this subscription's QoS.
        """
        if self._closed:
            raise Ros2Error(f"the subscription to {self.topic!r} is closed")
        if self.error is not None:
            raise self.error
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        self._next.append(future)
        try:
            return await future
        finally:
            if future in self._next:
                self._next.remove(future)

    def close(self) -> None:
        """Stop receiving; messages already queued are dropped."""
        if not self._closed:
            self._feed.close()
        error = self._close("destroy_subscription", self._sub, "subscription to")
        if error is not None:
            self._fail_waiters(error)

    def _fail_waiters(self, error: Exception) -> None:
        super()._fail_waiters(error)
        for future in self._next:
            if not future.done():
                future.set_exception(error)

    # -- on the loop ----------------------------------------------------------------

    def _deliver(self, message: Any) -> None:
        self.received += 1
        try:
            if self._mapping is not None:
                values = self._mapping(message)
                if values:
                    self._robot.state.update(values)
                    self.keys.update(values)
            if self._callback is not None:
                self._callback(message)
        except Exception:  # logged; the next message is delivered as usual
            _log.exception("a message on %s could not be delivered to the state", self.topic)
        if self._next:
            waiting, self._next = self._next, []
            for future in waiting:
                if not future.done():
                    future.set_result(message)

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"{self.received} received"
        return f"<Ros2Subscription {self.topic} {ros_name(self.msg_type)} {state}>"


class Ros2Publisher(_Endpoint, Generic[M]):
    """A publisher on a topic (made by `Ros2Node.publisher`); ``publish`` never blocks.

    A subscription whose QoS cannot match it (a transient-local one, this
    publisher volatile) is an error, logged once and kept as `error`.

    Attributes:
        topic: The topic's full name (namespace and remapping applied).
        msg_type: The message class.
        error: The `QosMismatchError` of a subscription that cannot match, or None.
    """

    msg_type: type[M]

    def __init__(self, thread: RosThread, topic: str, msg_type: type[M], qos: Any) -> None:
        super().__init__(thread, topic, msg_type, qos)
        self._pub = thread.node.create_publisher(
            msg_type, topic, qos, event_callbacks=self._events("PublisherEventCallbacks")
        )
        self._publish = self._pub.publish

    def publish(self, message: M) -> None:
        """Send ``message`` (an instance of `msg_type`) now.

        Raises:
            TypeError: ``message`` is of another type; both types are named.
            Ros2Error: The publisher is closed (or its robot stopped).
        """
        if self._closed:
            msg = f"the publisher on {self.topic!r} is closed (its robot stopped?)"
            raise Ros2Error(msg)
        try:
            self._publish(message)
        except TypeError as err:
            if isinstance(message, self.msg_type):
                raise
            msg = (
                f"the publisher on {self.topic!r} sends {ros_name(self.msg_type)}, "
                f"got {type(message).__module__}.{type(message).__qualname__}: {message!r}"
            )
            raise TypeError(msg) from err

    @property
    def subscribers(self) -> int:
        """How many subscriptions this publisher is matched with now."""
        return self.matches.count

    async def wait_for_subscribers(self, count: int = 1) -> int:
        """Return once at least ``count`` subscriptions are matched (wrap it in a timeout).

        Raises:
            QosMismatchError: One of the topic's subscriptions cannot match this QoS.
        """
        return await self._matched(count)

    def close(self) -> None:
        """Stop publishing; `publish` raises from now on."""
        error = self._close("destroy_publisher", self._pub, "publisher on")
        if error is not None:
            self._fail_waiters(error)

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"{self.subscribers} subscribers"
        return f"<Ros2Publisher {self.topic} {ros_name(self.msg_type)} {state}>"
