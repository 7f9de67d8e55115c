"""Fault injection at action boundaries: press the bumper when the Nth ``drive_distance`` starts.

The Create 3 random-walk script lost control whenever a bump came at the
wrong moment (during the undock, in its first drive). To test that a
behaviour survives a bump *anywhere*, `inject_bump` presses the bumper at a
chosen action boundary, and `inject_state` writes any state there: an
instrument watches the executive's events and, when the boundary comes,
writes ``robot.state`` on the next loop iteration, as a sensor update would.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Literal, Self

from .. import ActionFinished, ActionStarted, ExecEvent

if TYPE_CHECKING:
    from collections.abc import Mapping

    from .. import Robot

_log = logging.getLogger("pyrobots_aio.testing")

_BOUNDARIES: dict[str, type[ExecEvent]] = {"start": ActionStarted, "end": ActionFinished}
_SIDES = {"left": (True, False), "right": (False, True), "both": (True, True)}


class Injection:
    """A pending (then done) state write at an action boundary; made by `inject_state`.

    Use it as a context manager (``with inject_bump(robot, "undock") as bump:``)
    or call `remove` when done; either way nothing is left behind.

    Attributes:
        action: The name of the action whose boundary it waits for.
        nth: Which of the actions of that name (1: the first one to start or end).
        at: ``"start"`` (its body starts) or ``"end"`` (it is done, any outcome).
        time: The robot's time of the write, or None while it has not happened.
        action_id: The id of the action at whose boundary it wrote, or None.
    """

    def __init__(
        self,
        robot: Robot,
        action: str,
        values: Mapping[str, object],
        *,
        nth: int,
        at: Literal["start", "end"],
        release: Mapping[str, object] | None,
        hold: float | None,
    ) -> None:
        self.action, self.nth, self.at = action, nth, at
        self.time: float | None = None
        self.action_id: int | None = None
        self._robot, self._values, self._release, self._hold = robot, dict(values), release, hold
        self._kind = _BOUNDARIES[at]
        self._seen = 0
        self._scheduled: asyncio.Handle | None = None  # the write, then the release
        robot.instruments.add(self)

    @property
    def done(self) -> bool:
        """Whether the write has happened."""
        return self.time is not None

    def on_event(self, event: ExecEvent) -> None:
        """Count the boundaries of ``action``; at the ``nth``, write on the next iteration."""
        if type(event) is not self._kind or event.name != self.action:
            return
        self._seen += 1
        if self._seen == self.nth:
            self.action_id = event.action
            self._robot.instruments.remove(self)
            self._scheduled = asyncio.get_running_loop().call_soon(self._write)

    def _write(self) -> None:
        robot, self._scheduled = self._robot, None
        if not robot.is_running:
            return
        self.time = robot.time()
        _log.info("injected %s at the %s of %s #%d", self._values, self.at, self.action, self.nth)
        robot.state.update(self._values)
        if self._hold is not None and self._release is not None:
            self._scheduled = asyncio.get_running_loop().call_later(
                self._hold, robot.state.update, self._release
            )

    def remove(self) -> None:
        """Stop waiting for the boundary; drop a write or release not yet made."""
        self._robot.instruments.remove(self)
        if self._scheduled is not None:
            self._scheduled.cancel()
            self._scheduled = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.remove()

    def __repr__(self) -> str:
        when = f"written at t={self.time:.3f}" if self.time is not None else "pending"
        return f"<Injection {self._values} at the {self.at} of {self.action} #{self.nth}: {when}>"


def inject_state(
    robot: Robot,
    action: str,
    values: Mapping[str, object],
    *,
    nth: int = 1,
    at: Literal["start", "end"] = "start",
    release: Mapping[str, object] | None = None,
    hold: float | None = None,
) -> Injection:
    """Write ``values`` to ``robot.state`` when the ``nth`` action named ``action`` starts or ends.

    The write comes on the loop iteration after the boundary: at ``"start"``
    the action's body has run up to its first wait (a motion action is
    driving), at ``"end"`` whoever awaited the action has moved on to its
    next step. Actions are counted by name wherever they run (``undock``
    runs a ``drive_distance`` of its own; so does a bumper reflex). If the
    robot has stopped by then, nothing is written.

    Args:
        robot: The robot (running or about to run).
        action: The action's name, as in ``robot.running()`` and recordings.
        values: The state to write, in one update (monitors see it at once).
        nth: Which action of that name: 1 for the first to reach the boundary.
        at: ``"start"`` or ``"end"``.
        release: State to write ``hold`` seconds later (for a base that does
            not publish that state again by itself).
        hold: Seconds between ``values`` and ``release``.

    Raises:
        ValueError: A bad ``nth``, ``at``, or a ``hold`` without ``release``.
    """
    if isinstance(nth, bool) or not isinstance(nth, int) or nth < 1:
        msg = f"nth must be a whole number from 1 (the first {action!r}), got {nth!r}"
        raise ValueError(msg)
    if at not in _BOUNDARIES:
        msg = f"at must be 'start' or 'end', got {at!r}"
        raise ValueError(msg)
    if (hold is None) != (release is None) or (hold is not None and not hold >= 0):
        msg = f"give both release= and hold= (seconds, >= 0), or neither; got hold={hold!r}"
        raise ValueError(msg)
    return Injection(robot, action, values, nth=nth, at=at, release=release, hold=hold)


def inject_bump(
    robot: Robot,
    action: str,
    *,
    nth: int = 1,
    at: Literal["start", "end"] = "start",
    side: Literal["left", "right", "both"] = "both",
    hold: float | None = None,
) -> Injection:
    """Press the bumper (``bumper``, ``bumper_left``, ``bumper_right``) at an action boundary.

    One write presses it; the base's next sensor update releases it (the
    simulator and `FakeBase` publish the bumper every tick), or, with
    ``hold``, the injection writes the release itself that many seconds
    later. See `inject_state` for when the press comes.

    Examples:
        >>> from pyrobots_aio.sim import run
        >>> from pyrobots_aio.sim.random_walk import random_walk
        >>> from pyrobots_aio.testing import FakeBase
        >>> async def main() -> tuple[bool, int, bool]:
        ...     async with FakeBase() as robot:
        ...         with inject_bump(robot, "undock") as bump:  # a bump as it leaves the dock
        ...             report = await random_walk(robot, moves=2, seed=1)
        ...         return bump.done, report.bumps, report.docked
        >>> run(main)
        (True, 1, True)

    Raises:
        ValueError: A bad ``side`` (or an argument `inject_state` refuses).
    """
    if side not in _SIDES:
        msg = f"side must be 'left', 'right' or 'both', got {side!r}"
        raise ValueError(msg)
    left, right = _SIDES[side]
    pressed = {"bumper": True, "bumper_left": left, "bumper_right": right}
    released = dict.fromkeys(pressed, False) if hold is not None else None
    return inject_state(robot, action, pressed, nth=nth, at=at, release=released, hold=hold)
