"""How the bridge's subscriptions get their messages from DDS to the event loop.

Wherever it can, the loop takes them itself: DDS rings the subscription's
doorbell (an eventfd, see `_doorbell`) from its own thread, and the loop,
woken by its selector, takes what the subscription holds and delivers it
(`LoopFeed`). Nothing else wakes up, and no GIL changes hands.

Elsewhere, a receiver thread takes them (`ThreadFeed`). rclpy's executor
spends more on each message than taking it costs: it rebuilds its wait set
over every entity of the node, then wraps the callback in a task and two
coroutines (1.4-2x slower from topic to monitor than plain rclpy, measured
in separate processes). The `Receiver` waits on one wait set holding only
the bridge's subscriptions, their event handlers (matched counts, QoS
warnings) and a guard condition, and takes every message a ready
subscription holds, in order, as one batch handed to that subscription's
inbox, which the loop drains. Those subscriptions and their handlers belong
to a callback group in which rclpy's executor runs nothing: a subscription
and its events share one listener in the DDS layer, which wakes one wait
set only, so they must all be waited on here. For the same reason a
subscription the loop takes itself has its events rung too, never waited on.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ._doorbell import Doorbell, DoorbellUnavailable, doorbells_available
from ._rclpy import rclpy_module

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable, Coroutine, Mapping

_log = logging.getLogger("pyrobots_aio.ros2")

TAKEN_AT_ONCE = 64
"""Messages a `LoopFeed` takes and delivers in one turn of the loop at most.

A flood is then taken in turns, between which the loop runs what else is
ready: 1,000 messages taken at once held a loaded loop for 0.2-0.9 s.
"""


@dataclass(frozen=True, slots=True)
class _Entry:
    """One subscription the receiver takes from, and where its batches go."""

    subscription: Any
    deliver: Callable[[list[Any]], None]
    depth: int


def taken_elsewhere_group() -> Any:
    """A callback group of which rclpy's executor runs nothing: the receiver serves it."""
    reentrant = rclpy_module("rclpy.callback_groups").ReentrantCallbackGroup

    class TakenElsewhere(reentrant):  # type: ignore[misc,valid-type]
        def can_execute(self, entity: Any) -> bool:
            return False

        def beginning_execution(self, entity: Any) -> bool:
            return False

    return TakenElsewhere()


class Receiver:
    """Takes the messages of its subscriptions on its own thread; started by the first one.

    Args:
        name: The node's name (the thread is named after it).
        context: The node's rclpy context.
        bound: Seconds one wait lasts at most before the thread looks whether to stop.

    Attributes:
        group: The callback group of every subscription of the bridge's (rclpy's
            executor runs none of them).
        doorbells: Whether a new subscription is tried with a `LoopFeed` first
            (cleared once the RMW refuses one).
    """

    def __init__(self, name: str, context: Any, bound: float) -> None:
        self.group = taken_elsewhere_group()
        self.doorbells = doorbells_available()
        self._name = name
        self._context = context
        self._bound_ns = int(bound * 1e9)
        self._implementation = _implementation()
        self._guard = rclpy_module("rclpy.guard_condition").GuardCondition(
            None, None, context=context
        )
        self._entries: list[_Entry] = []
        self._lock = threading.Lock()  # guards the entries and the thread's start
        self._changed = False
        self._stopping = False
        self._stopped = threading.Event()
        self._thread: threading.Thread | None = None

    def add(self, subscription: Any, deliver: Callable[[list[Any]], None], depth: int) -> None:
        """Take ``subscription``'s messages from now on: ``deliver(batch)`` on this thread."""
        with self._lock:
            self._entries.append(_Entry(subscription, deliver, depth))
            if self._thread is None:
                self._thread = threading.Thread(
                    target=self._run, name=f"pyrobots_aio.ros2 {self._name} receiver", daemon=True
                )
                self._thread.start()
        self._wake()

    def remove(self, subscription: Any) -> None:
        """Stop taking ``subscription``'s messages (before it is destroyed)."""
        with self._lock:
            self._entries = [e for e in self._entries if e.subscription is not subscription]
        self._wake()

    def stop(self, join_bound: float) -> None:
        """End the thread (within ``join_bound`` seconds) and destroy the guard condition."""
        self._stopping = True
        self._stopped.set()
        self._wake()
        if self._thread is not None:
            self._thread.join(join_bound)
            if self._thread.is_alive():
                _log.error(
                    "the ROS 2 receiver of node %s did not end within %s s", self._name, join_bound
                )
        self._guard.destroy()

    def _wake(self) -> None:
        self._changed = True
        with contextlib.suppress(self._implementation.InvalidHandle):  # stopped already
            self._guard.trigger()

    # -- on the receiver's thread -------------------------------------------------------

    def _run(self) -> None:
        while not self._stopping:
            with self._lock:
                entries = list(self._entries)
                self._changed = False
            try:
                self._serve(entries)
            except Exception:  # logged; the next round, a bound later, builds its wait set anew
                _log.exception("the ROS 2 receiver of node %s failed", self._name)
                self._stopped.wait(self._bound_ns / 1e9)

    def _serve(self, entries: list[_Entry]) -> None:
        """Wait and take, until the set of subscriptions changes or the node stops."""
        invalid = self._implementation.InvalidHandle
        with contextlib.ExitStack() as held:  # what is waited on is not destroyed meanwhile
            live, handlers = [], []
            for entry in entries:
                with contextlib.suppress(invalid):  # destroyed: it is being removed
                    held.enter_context(entry.subscription.handle)
                    live.append(entry)
                    for handler in entry.subscription.event_handlers:
                        held.enter_context(handler)
                        handlers.append(handler)
            guard, context = self._guard.handle, self._context.handle
            held.enter_context(guard)
            held.enter_context(context)
            events = sum(h.get_num_entities().num_events for h in handlers)
            wait_set = self._implementation.WaitSet(len(live), 1, 0, 0, 0, events, context)
            held.callback(wait_set.destroy_when_not_in_use)  # first, while the rest is held
            while not (self._changed or self._stopping):
                wait_set.clear_entities()
                for entry in live:
                    wait_set.add_subscription(entry.subscription.handle)
                for handler in handlers:
                    handler.add_to_wait_set(wait_set)
                wait_set.add_guard_condition(guard)
                wait_set.wait(self._bound_ns)
                ready = wait_set.get_ready_entities("subscription")
                for entry in live:
                    with contextlib.suppress(invalid):  # closed meanwhile: the next round drops it
                        if entry.subscription.handle.pointer in ready:
                            _take(entry)
                for handler in handlers:
                    with contextlib.suppress(invalid):  # its subscription closed meanwhile
                        if handler.is_ready(wait_set):
                            _run_to_end(handler.execute(handler.take_data()))


def _take(entry: _Entry) -> None:
    """Take what ``entry``'s subscription holds (at most its depth), in order; deliver it."""
    subscription = entry.subscription
    handle, msg_type, raw = subscription.handle, subscription.msg_type, subscription.raw
    batch: list[Any] = []
    while len(batch) < entry.depth:
        taken = handle.take_message(msg_type, raw)
        if taken is None:
            break
        batch.append(taken[0])
    if batch:
        entry.deliver(batch)


def _run_to_end(coroutine: Coroutine[Any, Any, object]) -> None:
    """Run an event handler's ``execute`` (a coroutine that calls a plain callback) now."""
    try:
        coroutine.send(None)
    except StopIteration:
        return
    coroutine.close()
    _log.error("a ROS 2 event handler awaited something; its callback was abandoned")


# -- feeds: a subscription's messages, delivered on the loop one by one, in order ----------


class _Event:
    """An event of a subscription (a matched count, a QoS mismatch), rung like its messages."""

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        parent: Any,
        event_type: Any,
        callback: Callable[[Any], None],
    ) -> None:
        with parent:  # UnsupportedEventTypeError: this RMW does not tell it
            self._handle = _implementation().EventHandle(parent, event_type)
        self._callback = callback
        try:
            self._bell = Doorbell(loop, self._handle, self._rung, event=True)
        except DoorbellUnavailable:
            self._handle.destroy_when_not_in_use()
            raise

    def _rung(self) -> None:
        self._bell.rings()
        info = None
        with contextlib.suppress(_implementation().InvalidHandle), self._handle:
            info = self._handle.take_event()
        if info is not None:
            self._callback(info)

    def close(self) -> None:
        self._bell.close()
        self._handle.destroy_when_not_in_use()


class LoopFeed:
    """A subscription the loop takes from itself, when DDS rings its doorbell.

    DDS keeps at most ``depth`` messages for the subscription (its history);
    the doorbell counts the messages that arrive, so those that arrived and
    were neither taken nor kept were dropped (overwritten, oldest first).
    `queued` and `dropped` are read on the loop.

    Args:
        loop: The event loop, where everything here runs.
        subscription: The rclpy subscription (created without event handlers).
        depth: Its history depth: DDS keeps that many messages for the loop.
        deliver: Called with each message, in order.
        events: Event types of the subscription (rclpy's
            ``QoSSubscriptionEventType``), each with the callback given what the
            event takes; a type the RMW does not support is left out.

    Raises:
        DoorbellUnavailable: The subscription cannot ring the loop (nothing is left hung).
    """

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        subscription: Any,
        depth: int,
        deliver: Callable[[Any], None],
        events: Mapping[Any, Callable[[Any], None]],
    ) -> None:
        self.arrived = self.taken = self._dropped = 0
        self._loop, self._depth, self._deliver = loop, depth, deliver
        self._handle = subscription.handle
        self._msg_type, self._raw = subscription.msg_type, subscription.raw
        self._invalid = _implementation().InvalidHandle
        self._closed = self._pending = False
        self._events: list[_Event] = []
        self._bell: Doorbell | None = None
        try:
            for event_type, callback in events.items():
                with contextlib.suppress(_implementation().UnsupportedEventTypeError):
                    self._events.append(_Event(loop, self._handle, event_type, callback))
            self._bell = Doorbell(loop, self._handle, self._rung)
        except DoorbellUnavailable:
            self.close()
            raise

    @property
    def queued(self) -> int:
        """Messages DDS holds for the loop (arrived, not taken yet, not dropped)."""
        self._look()
        return max(0, self.arrived - self.taken - self._dropped)

    @property
    def dropped(self) -> int:
        """Messages DDS dropped (overwrote) before the loop took them."""
        self._look()
        return self._dropped

    def _look(self) -> None:
        """Count the arrivals rung for; those beyond what the history holds were dropped."""
        rang = 0 if self._bell is None or self._closed else self._bell.rings()
        if not rang:
            return
        self.arrived += rang
        self._dropped += max(0, self.arrived - self.taken - self._dropped - self._depth)
        if not self._pending:  # read here, the bell will not wake the loop for them
            self._pending = True
            self._loop.call_soon_threadsafe(self._take)

    def _rung(self) -> None:
        if self._bell is not None and not self._closed:
            self.arrived += self._bell.rings()
            if not self._pending:  # else a turn of taking is due already
                self._take()

    def _take(self) -> None:
        """Take and deliver what the subscription holds, `TAKEN_AT_ONCE` messages at most."""
        self._pending = False
        take, msg_type, raw = self._handle.take_message, self._msg_type, self._raw
        deliver = self._deliver
        with contextlib.suppress(self._invalid), self._handle:
            for _ in range(TAKEN_AT_ONCE):
                if self._closed:  # before, or by a delivery
                    return
                taken = take(msg_type, raw)
                if taken is None:  # all taken: every arrival counted is delivered or dropped
                    self._dropped = max(self._dropped, self.arrived - self.taken)
                    return
                self.taken += 1
                deliver(taken[0])
            self._pending = True  # maybe more: after what else is ready on the loop
            self._loop.call_soon(self._take)

    def close(self) -> None:
        """Unhang every bell (DDS rings no more) and let the event handles go."""
        self._closed = True
        if self._bell is not None:
            self._bell.close()
        for event in self._events:
            event.close()
        self._events.clear()


class ThreadFeed:
    """A subscription the receiver thread takes from, its batches drained on the loop.

    The receiver puts each batch in the inbox and, if the inbox was empty,
    schedules one drain with ``to_loop``; the drain delivers every queued
    message, in order. The inbox holds at most ``depth`` messages: if the loop
    falls that far behind, the oldest are dropped (and counted), as a ROS 2
    ``KEEP_LAST`` queue would.
    """

    def __init__(
        self,
        receiver: Receiver,
        subscription: Any,
        depth: int,
        to_loop: Callable[[Callable[[], None]], None],
        deliver: Callable[[Any], None],
    ) -> None:
        self.dropped = 0
        self._receiver, self._subscription = receiver, subscription
        self._depth, self._to_loop, self._deliver = depth, to_loop, deliver
        self._inbox: deque[Any] = deque(maxlen=depth)
        self._lock = threading.Lock()
        self._scheduled = self._closed = False
        receiver.add(subscription, self._on_batch, depth)

    @property
    def queued(self) -> int:
        """Messages taken from DDS and not delivered yet (the loop's lag)."""
        with self._lock:
            return len(self._inbox)

    def _on_batch(self, messages: list[Any]) -> None:  # on the receiver's thread
        with self._lock:
            # the inbox keeps the newest `depth` messages: count those it is about to drop
            self.dropped += max(0, len(self._inbox) + len(messages) - self._depth)
            self._inbox.extend(messages)
            if self._scheduled:
                return
            self._scheduled = True
        self._to_loop(self._drain)

    def _drain(self) -> None:
        with self._lock:
            messages = list(self._inbox)
            self._inbox.clear()
            self._scheduled = False
        for message in messages:
            if self._closed:
                return
            self._deliver(message)

    def close(self) -> None:
        """Stop taking (messages queued are dropped)."""
        if not self._closed:
            self._closed = True
            self._receiver.remove(self._subscription)


def taken_elsewhere(_message: Any) -> None:
    """The callback rclpy is given for the bridge's subscriptions, and never runs (their group)."""


def _implementation() -> Any:
    return rclpy_module("rclpy.impl.implementation_singleton").rclpy_implementation
