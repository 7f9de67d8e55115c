"""The emergency stop: latched, it stops the actuators and preempts every resource holder.

``robot.emergency_stop(reason)`` does its work at the call, in this order, so
that nothing (a busy queue, ``max_actions``, a task not yet scheduled) delays
it: it latches, stops the actuators (`EmergencyStop.halt_actuators`; a
`pyrobots_aio.DriveBase` stops its wheels), starts the ``emergency_stop``
action in the robot's root scope, never refused by ``max_actions``, and
cancels every action that holds or waits for a resource, whatever its lock
priority, and every action a supervisor hands it (`add_emergency_stop_callback`:
a ``retry`` hands its retrying action, a ``StateMachine`` its current state's),
on that action's behalf. The action only waits until they are all done (their
cleanup included). Motion stays refused (`EmergencyStopError`) until
``robot.clear_emergency_stop()``.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from .._exceptions import EmergencyStopError
from ..actions import ActionHandle, current_action

if TYPE_CHECKING:
    from .._core._logging import ScopedLogger
    from ..actions._executive import Executive
    from ..state import StateStore

StopCallback = Callable[[str], Iterable[ActionHandle[Any]]]
"""A supervisor's part in the emergency stop: given the reason, the actions to stop too."""

STOPPED_KEY = "emergency_stop"
"""State key: True while the emergency stop is latched (written at its first use)."""
REASON_KEY = "emergency_stop_reason"
"""State key: the reason of the latched emergency stop, None once cleared."""


class EmergencyStop:
    """The emergency stop of a `Robot` (a mixin: `Robot` is the class to use)."""

    state: StateStore
    executive: Executive
    _estop_reason: str | None = None
    _estop_callbacks: dict[StopCallback, None] | None = None  # an ordered set, made at first use

    @property
    def emergency_stopped(self) -> bool:
        """Whether the emergency stop is latched (motion is refused until cleared)."""
        return self._estop_reason is not None

    @property
    def emergency_stop_reason(self) -> str | None:
        """The reason the latched emergency stop was first given, or None."""
        return self._estop_reason

    def halt_actuators(self) -> None:
        """Stop every actuator at once; the emergency stop calls it first.

        A bare robot has none; a `pyrobots_aio.DriveBase` stops its wheels. A
        robot with other actuators overrides it (and calls ``super()``). It
        must not await, nor raise: an error is logged and the stop goes on.
        """

    def emergency_stop(self, reason: str = "emergency stop") -> ActionHandle[None]:
        """Latch the emergency stop: halt the actuators, preempt every resource holder.

        At the call: the stop latches (`emergency_stopped`; the state keys
        ``emergency_stop`` and ``emergency_stop_reason``), `halt_actuators`
        runs, and every action that holds or waits for a resource is cancelled
        with the reason ``"emergency stop: <reason>"``, whatever its lock
        priority, with its subtree; so are the supervised plans (a running
        ``retry``, a ``StateMachine``'s current state: see
        `add_emergency_stop_callback`). Until `clear_emergency_stop`,
        ``drive`` and the motion actions refuse to move
        (`EmergencyStopError`). The returned
        ``emergency_stop`` action (root scope, never refused by
        ``max_actions``) ends once those actions are done, cleanup included.
        Calling it again while latched preempts the holders of that moment
        and keeps the first reason. It is a plain call, so any event can
        trigger it: ``robot.whenever("cliff_front_left",
        becomes=True).do(robot.emergency_stop, "cliff")``.

        Raises:
            RobotNotRunningError: The robot is not running (or shutting down:
                it is stopped all the same, then this is raised).
            EventLoopError: Called from another thread (use
                ``robot.call_soon_threadsafe(robot.emergency_stop, reason)``).

        Examples:
            >>> from pyrobots_aio import ActionInterrupted, Resource, Robot, action, lock
            >>> from pyrobots_aio.sim import run
            >>> @action
            ... @lock(Resource("arm"))
            ... async def wave(robot: Robot) -> None:
            ...     await robot.sleep(60)
            >>> async def main() -> tuple[str | None, bool]:
            ...     async with Robot(actions=[wave]) as robot:
            ...         waving = robot.wave()
            ...         await robot.sleep(1)
            ...         await robot.emergency_stop("operator")
            ...         try:
            ...             await waving
            ...         except ActionInterrupted as stop:
            ...             return stop.reason, robot.state.emergency_stop
            ...     return None, False
            >>> run(main)
            ('emergency stop: operator', True)
        """
        executive = self.executive
        executive.check_loop("emergency stop")
        if self._estop_reason is None:
            self._estop_reason = reason
            self.state.update({STOPPED_KEY: True, REASON_KEY: reason})
        log = executive.log_scope.logger("pyrobots_aio.robot")
        try:
            self.halt_actuators()
        except Exception:
            log.exception("halt_actuators() failed during the emergency stop (%s)", reason)
        holders = self._to_preempt(reason, log)
        log.warning(
            "emergency stop: %s; preempting %s",
            reason,
            ", ".join(f"{h.name}#{h.id}" for h in holders) or "nothing",
        )
        token = current_action.set(None)  # the root scope: no holder's cancellation reaches it
        try:
            handle = executive.spawn(
                "emergency_stop", _wait_until_done, _wait_until_done(executive, holders),
                uncapped=True,
            )  # fmt: skip
        except Exception:
            _cancel(holders, f"emergency stop: {reason}", None)
            raise
        finally:
            current_action.reset(token)
        _cancel(holders, f"emergency stop: {reason}", handle)
        return handle

    def add_emergency_stop_callback(self, callback: StopCallback) -> None:
        """Call ``callback(reason)`` at each emergency stop; it returns more actions to stop.

        How a supervisor takes part in the stop (`retry` hands over its
        retrying action, a `StateMachine` its current state's action): at each
        call of `emergency_stop`, once it has latched and halted the actuators,
        ``callback`` gets that call's reason and returns the actions to cancel
        with the resource holders (the same reason, on the stop's behalf, with
        their subtrees; the ``emergency_stop`` action waits for them too). It
        must not await; an error in it is logged and the stop goes on. Until
        `remove_emergency_stop_callback`; adding it twice adds it once.

        Raises:
            TypeError: ``callback`` is not callable.
        """
        given: object = callback  # checked at run time: the annotation promises nothing
        if not callable(given):
            msg = (
                f"an emergency stop callback must be callable as callback(reason), got "
                f"{callback!r}; pass a function returning the actions to stop"
            )
            raise TypeError(msg)
        if self._estop_callbacks is None:
            self._estop_callbacks = {}
        self._estop_callbacks[callback] = None

    def remove_emergency_stop_callback(self, callback: StopCallback) -> None:
        """Stop calling ``callback`` at emergency stops (nothing if it was not added)."""
        if self._estop_callbacks is not None:
            self._estop_callbacks.pop(callback, None)

    def clear_emergency_stop(self) -> None:
        """Release the latched emergency stop: motion is allowed again (nothing restarts).

        Clearing a stop that is not latched does nothing.

        Raises:
            EventLoopError: Called from another thread while the robot runs (use
                ``robot.call_soon_threadsafe(robot.clear_emergency_stop)``).
        """
        if self.executive.is_running:  # (the latch outlives a run: clearing it between is fine)
            self.executive.check_loop("clear the emergency stop")
        if self._estop_reason is None:
            return
        log = self.executive.log_scope.logger("pyrobots_aio.robot")
        log.info("emergency stop cleared (it was: %s)", self._estop_reason)
        self._estop_reason = None
        self.state.update({STOPPED_KEY: False, REASON_KEY: None})

    def _to_preempt(self, reason: str, log: ScopedLogger) -> list[ActionHandle[Any]]:
        """Every action holding or awaiting a resource, then those the callbacks hand over."""
        preempted = dict.fromkeys(h for h in self.executive.running() if h.held or h.awaiting)
        for callback in tuple(self._estop_callbacks or ()):
            try:
                preempted.update(dict.fromkeys(callback(reason)))
            except Exception:
                log.exception("an emergency stop callback failed (%s): %r", reason, callback)
        return [h for h in preempted if not h.done()]

    def _refuse_motion(self, what: str) -> None:
        """Raise `EmergencyStopError` for ``what`` if the emergency stop is latched."""
        if self._estop_reason is not None:
            raise EmergencyStopError(what, self._estop_reason)


def _cancel(holders: list[ActionHandle[Any]], reason: str, by: ActionHandle[Any] | None) -> None:
    """Cancel ``holders`` on behalf of ``by`` (the stop's action), not of the caller."""
    token = current_action.set(by)  # the canceller `cancel` records: the action running now
    try:
        for holder in holders:
            holder.cancel(reason)
    finally:
        current_action.reset(token)


async def _wait_until_done(executive: Executive, holders: list[ActionHandle[Any]]) -> None:
    """The body of the ``emergency_stop`` action: wait for the preempted actions to be done."""
    waiting: asyncio.Future[None] = executive.all_done(holders)
    await waiting
