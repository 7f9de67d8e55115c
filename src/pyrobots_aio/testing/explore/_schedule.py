"""Schedules of disturbances: what hits the robot (`Bump`, `Pause` ...) and when (`On`, `At`).

Every value here is frozen and its ``repr`` is the code that builds it, so a
shrunk schedule prints as a list that, pasted into a test, replays it.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, ClassVar, Literal

from ...actions import action, lock
from ...motion import WHEELS, DriveBase
from ._tamper import Tamper

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

    from ... import Robot

PREEMPT_PRIORITY = 1000
"""`Preempt`'s priority: above any reflex a behaviour brings."""


def _code(value: Any) -> str:
    """``value`` as the code that builds it: its first field, then by keyword, defaults unsaid."""
    given = [(f, getattr(value, f.name)) for f in fields(value)]
    said = [(f, v) for f, v in given if v != f.default]
    first = [repr(v) for f, v in said[:1] if f is given[0][0]]
    keywords = [f"{f.name}={v!r}" for f, v in said[len(first) :]]
    return f"{type(value).__name__}({', '.join(first + keywords)})"


# -- when -------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, repr=False)
class On:
    """At a boundary: when the ``nth`` action named ``action`` starts (or ends, ``at="end"``).

    Actions are counted by name wherever they run, as `inject_state` counts them.
    """

    action: str
    nth: int = 1
    at: Literal["start", "end"] = "start"

    def __repr__(self) -> str:
        return _code(self)


@dataclass(frozen=True, slots=True, repr=False)
class At:
    """At a virtual time: ``time`` seconds after the behaviour started."""

    time: float

    def __repr__(self) -> str:
        return _code(self)


When = On | At


# -- what -------------------------------------------------------------------------------------


class Disturbance(abc.ABC):
    """Something that happens to the robot; a subclass is a frozen dataclass, its repr code."""

    @abc.abstractmethod
    def apply(self, target: Target) -> None:
        """Make it happen now, on ``target``'s robot (a plain call on the loop)."""

    def __repr__(self) -> str:
        return _code(self)


def _pressed(target: Target, values: dict[str, object], hold: float) -> None:
    """Write ``values`` now; with ``hold``, the base reads them for ``hold`` seconds more."""
    target.robot.state.update(values)
    if hold > 0:
        target.tamper().force(values, hold)


@dataclass(frozen=True, slots=True, repr=False)
class Bump(Disturbance):
    """The front bumper pressed on ``side``, for one reading or ``hold`` seconds."""

    side: Literal["both", "left", "right"] = "both"
    hold: float = 0.0

    SIDES: ClassVar[tuple[str, ...]] = ("both", "left", "right")

    def apply(self, target: Target) -> None:
        left, right = self.side != "right", self.side != "left"
        _pressed(target, {"bumper": True, "bumper_left": left, "bumper_right": right}, self.hold)


@dataclass(frozen=True, slots=True, repr=False)
class Cliff(Disturbance):
    """The cliff sensor ``cliff_<position>`` sees a drop, for one reading or ``hold`` seconds."""

    position: str = "front_left"
    hold: float = 0.0

    POSITIONS: ClassVar[tuple[str, ...]] = ("front_left", "front_right", "side_left", "side_right")

    def apply(self, target: Target) -> None:
        _pressed(target, {f"cliff_{self.position}": True}, self.hold)


@dataclass(frozen=True, slots=True, repr=False)
class Reading(Disturbance):
    """The range sensor ``ir_<position>`` reads ``metres``, for one reading or ``hold`` seconds."""

    position: str = "front_center"
    metres: float = 0.02
    hold: float = 0.0

    POSITIONS: ClassVar[tuple[str, ...]] = (
        "front_center",
        "front_center_left",
        "front_center_right",
        "front_left",
        "front_right",
        "left",
        "right",
    )

    def apply(self, target: Target) -> None:
        _pressed(target, {f"ir_{self.position}": self.metres}, self.hold)


@dataclass(frozen=True, slots=True, repr=False)
class Silence(Disturbance):
    """The base stops publishing ``key`` for ``seconds``: the state keeps its last value."""

    key: str = "bumper"
    seconds: float = 1.0

    def apply(self, target: Target) -> None:
        target.tamper().silence(self.key, self.seconds)


@dataclass(frozen=True, slots=True, repr=False)
class StaleOdometry(Disturbance):
    """The odometry stops moving for ``seconds`` (the wheels' encoders froze)."""

    seconds: float = 1.0

    def apply(self, target: Target) -> None:
        target.tamper().freeze_odometry(self.seconds)


@dataclass(frozen=True, slots=True, repr=False)
class Pause(Disturbance):
    """``robot.pause_all()``, then ``robot.resume_all()`` ``seconds`` later."""

    seconds: float = 1.0

    def apply(self, target: Target) -> None:
        target.robot.pause_all("explore: Pause")
        target.later(self.seconds, target.robot.resume_all)


@dataclass(frozen=True, slots=True, repr=False)
class Cancel(Disturbance):
    """Cancel the newest running action named ``action`` (any action's, with None)."""

    action: str | None = None

    def apply(self, target: Target) -> None:
        for handle in reversed(target.robot.handles()):
            if not handle.done() and self.action in (None, handle.name):
                handle.cancel("explore: Cancel")
                return


@dataclass(frozen=True, slots=True, repr=False)
class EmergencyStop(Disturbance):
    """``robot.emergency_stop()``, cleared ``clear_after`` seconds later (never, with None)."""

    clear_after: float | None = 1.0

    def apply(self, target: Target) -> None:
        target.robot.emergency_stop("explore: EmergencyStop")
        if self.clear_after is not None:
            target.later(self.clear_after, target.robot.clear_emergency_stop)


@action
@lock(WHEELS, priority=PREEMPT_PRIORITY, preempt=True)
async def preempting_reflex(robot: DriveBase, seconds: float) -> None:
    """Take the wheels from whoever holds them and stand still for ``seconds``."""
    robot.stop()
    await robot.sleep(seconds)


@dataclass(frozen=True, slots=True, repr=False)
class Preempt(Disturbance):
    """A reflex takes the wheels (``preempt=True``, `PREEMPT_PRIORITY`) and stands still."""

    seconds: float = 0.5

    def apply(self, target: Target) -> None:
        robot = target.robot
        if not isinstance(robot, DriveBase):
            msg = f"Preempt takes a DriveBase's wheels; {robot!r} is not a DriveBase"
            raise TypeError(msg)
        preempting_reflex(robot, self.seconds)


@dataclass(frozen=True, slots=True)
class Hit:
    """One disturbance of a schedule, and when it comes."""

    what: Disturbance
    when: When

    def __repr__(self) -> str:
        return f"Hit({self.what!r}, {self.when!r})"


# -- on the robot ----------------------------------------------------------------------------


class Target:
    """A running robot under a schedule: what disturbances act on, and what undoes them."""

    def __init__(self, robot: Robot, loop: asyncio.AbstractEventLoop) -> None:
        self.robot, self._loop = robot, loop
        self._tamper: Tamper | None = None
        self._pending: list[asyncio.Handle] = []

    def tamper(self) -> Tamper:
        """The base's readings, tampered with (installed on first use)."""
        if self._tamper is None:
            self._tamper = Tamper.install(self.robot)
        return self._tamper

    def later(self, seconds: float, fn: Callable[[], object]) -> None:
        """Call ``fn()`` in ``seconds``, unless the run ends first."""
        self._pending.append(self._loop.call_later(seconds, fn))

    def undo(self) -> None:
        """Drop whatever is still to come and give the base back its own readings."""
        for handle in self._pending:
            handle.cancel()
        if self._tamper is not None:
            self._tamper.remove()
