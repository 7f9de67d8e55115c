"""The receiver: the bridge's subscriptions taken from DDS on a thread of their own.

rclpy's executor spends more on each message than taking it costs: it
rebuilds its wait set over every entity of the node, then wraps the callback
in a task and two coroutines. Measured beside a plain rclpy subscription in
another process, that cost, paid before the message could even cross to
the event loop, made the bridge 1.4-2x slower from topic to monitor.

The receiver waits on one wait set holding only the bridge's subscriptions,
their event handlers (matched counts, QoS warnings) and a guard condition,
and takes every message a ready subscription holds, in order, as one batch
handed to that subscription. Those subscriptions and their handlers belong
to a callback group in which rclpy's executor runs nothing: a subscription
and its events share one listener in the DDS layer, which wakes one wait
set only, so they must all be waited on here.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ._rclpy import rclpy_module

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

_log = logging.getLogger("pyrobots_aio.ros2")


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
    """

    def __init__(self, name: str, context: Any, bound: float) -> None:
        self.group = taken_elsewhere_group()
        self._name = name
        self._context = context
        self._bound_ns = int(bound * 1e9)
        self._implementation = rclpy_module(
            "rclpy.impl.implementation_singleton"
        ).rclpy_implementation
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
