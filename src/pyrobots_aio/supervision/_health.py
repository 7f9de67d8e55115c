"""HealthMonitor: heartbeats and staleness of state keys and subsystems, as levels in the state.

Each watched thing (a state key, whose every write is a heartbeat; or a
subsystem, which calls `HealthMonitor.beat`) has a level, ``ok``, ``warn``,
``error`` or ``stale`` (diagnostic_msgs' four, in the same order), written to
``robot.state`` on each change, so monitors can act on a transition and
recorders keep it. Staleness needs no polling: each thing has at most one
loop timer, due when its next threshold (``warn_after``, then
``stale_after``) would pass without a heartbeat. A heartbeat only stores its
time; the timer, when due, finds the fresh heartbeat and moves itself to the
new deadline. So a thing that stays fresh costs one timer call per threshold
period, and one that stays stale costs nothing.
"""

from __future__ import annotations

import asyncio
import enum
import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._exceptions import StateError
from ..actions import Action, current_action
from ._timeout import check_seconds

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..actions import ActionHandle
    from ..robot import Robot
    from ..state import Subscription

_log = logging.getLogger("pyrobots_aio.supervision")
_EPSILON = 1e-9  # a timer may fire a hair before its deadline (the loop's clock resolution)


class HealthLevel(enum.StrEnum):
    """How healthy a watched thing is; it compares equal to its string value (``"ok"`` ...).

    The order is diagnostic_msgs' (``DiagnosticStatus``): OK < WARN < ERROR <
    STALE, and `diagnostic` gives the byte it publishes.
    """

    OK = "ok"
    WARN = "warn"
    ERROR = "error"
    STALE = "stale"
    """No heartbeat for ``stale_after`` seconds (or none yet)."""

    @property
    def diagnostic(self) -> int:
        """The ``diagnostic_msgs/DiagnosticStatus`` level: 0 OK, 1 WARN, 2 ERROR, 3 STALE."""
        return _ORDER[self]


_ORDER = {HealthLevel.OK: 0, HealthLevel.WARN: 1, HealthLevel.ERROR: 2, HealthLevel.STALE: 3}
_BY_VALUE = {level.value: level for level in HealthLevel}


@dataclass(frozen=True, slots=True)
class HealthStatus:
    """The health of one watched thing at one moment (what ``/diagnostics`` publishes).

    Attributes:
        name: The name it is watched under.
        level: Its level.
        message: Why (empty when ok).
        key: The state key it watches, or None for a subsystem.
        since: Loop time at which it entered this level.
        last_seen: Loop time of its last heartbeat, or None if none yet.
    """

    name: str
    level: HealthLevel
    message: str
    key: str | None
    since: float
    last_seen: float | None


class _Watched:
    """One watched thing: its thresholds, its last heartbeat, its timer and its status."""

    __slots__ = (
        "check",
        "fresh",
        "key",
        "last",
        "name",
        "reported",
        "shown",
        "since",
        "stale_after",
        "timer",
        "warn_after",
    )

    def __init__(
        self,
        name: str,
        key: str | None,
        warn_after: float | None,
        stale_after: float | None,
        check: Callable[[Any], object] | None,
    ) -> None:
        self.name, self.key, self.check = name, key, check
        self.warn_after, self.stale_after = warn_after, stale_after
        self.last: float | None = None
        self.fresh = (HealthLevel.STALE, "no heartbeat yet")
        self.reported = (HealthLevel.OK, "")
        self.shown: tuple[HealthLevel, str] | None = None  # as last published
        self.since = 0.0
        self.timer: asyncio.TimerHandle | None = None

    def freshness(self, now: float) -> tuple[HealthLevel, str]:
        """The level that the time since the last heartbeat gives."""
        if self.last is None:
            return HealthLevel.STALE, "no heartbeat yet"
        gap = now - self.last + _EPSILON
        if self.stale_after is not None and gap >= self.stale_after:
            return HealthLevel.STALE, f"no heartbeat for {self.stale_after:g} s"
        if self.warn_after is not None and gap >= self.warn_after:
            return HealthLevel.WARN, f"no heartbeat for {self.warn_after:g} s"
        return HealthLevel.OK, ""

    def next_deadline(self, now: float) -> float | None:
        """When the next threshold passes without a heartbeat (None: none left)."""
        if self.last is None:
            return None
        gap = now - self.last + _EPSILON
        ahead = [t for t in (self.warn_after, self.stale_after) if t is not None and t > gap]
        return self.last + min(ahead) if ahead else None

    def level(self) -> tuple[HealthLevel, str]:
        """The worse of freshness and the reported (or checked) level."""
        return max(self.fresh, self.reported, key=lambda pair: _ORDER[pair[0]])

    def status(self) -> HealthStatus:
        """Its published status, as a value."""
        level, message = self.shown or (HealthLevel.STALE, "not started")
        return HealthStatus(self.name, level, message, self.key, self.since, self.last)


class HealthMonitor:
    """Heartbeats and staleness per state key or subsystem, with levels in ``robot.state``.

    Watch state keys (`watch`: every write is a heartbeat, and an optional
    ``check`` grades the value) and subsystems (`subsystem`: they call
    `beat`), then `start` it: an action, ``health_monitor``, that runs until
    cancelled (the robot's exit cancels it). Each thing's level is written to
    the state key ``<prefix>_<name>`` (``health_camera``: ``"ok"``,
    ``"warn"``, ``"error"`` or ``"stale"``, as `HealthLevel`) and the worst of
    all to ``<prefix>`` (``health``), at each change only: monitors on them
    trigger actions on a transition, recordings keep them. `statuses` and
    `subscribe` give the full `HealthStatus` (message, times), for a
    ``/diagnostics`` publisher.

    Before its first heartbeat a thing is ``stale``.

    Args:
        robot: The robot whose state it watches and writes.
        prefix: The prefix of the state keys it writes.

    Examples:
        >>> from pyrobots_aio import Robot
        >>> from pyrobots_aio.sim import run
        >>> async def main() -> list[str]:
        ...     async with Robot() as robot:
        ...         robot.state.camera = 0
        ...         health = HealthMonitor(robot)
        ...         health.watch("camera", warn_after=0.1, stale_after=1.0)
        ...         health.start()
        ...         seen = [robot.state.health_camera]
        ...         await robot.sleep(0.5)  # no frame for 0.5 s
        ...         seen.append(robot.state.health_camera)
        ...         robot.state.camera = 1  # a frame: fresh again
        ...         seen.append(robot.state.health_camera)
        ...         await robot.sleep(2.0)
        ...         return [*seen, robot.state.health_camera, robot.state.health]
        >>> run(main)
        ['ok', 'warn', 'ok', 'stale', 'stale']
    """

    def __init__(self, robot: Robot, *, prefix: str = "health") -> None:
        if not isinstance(prefix, str) or not prefix:
            msg = f"HealthMonitor prefix must be a non-empty string, got {prefix!r}"
            raise ValueError(msg)
        self.robot = robot
        self.prefix = prefix
        self._watched: dict[str, _Watched] = {}
        self._subscriptions: list[Subscription] = []
        self._listeners: list[Callable[[HealthStatus], object]] = []
        self._handle: ActionHandle[None] | None = None
        self._overall: HealthLevel | None = None

    # -- what to watch ------------------------------------------------------------

    def watch(
        self,
        key: str,
        *,
        name: str | None = None,
        warn_after: float | None = None,
        stale_after: float | None = None,
        check: Callable[[Any], HealthLevel | str | tuple[HealthLevel | str, str]] | None = None,
    ) -> None:
        """Watch the state key ``key``: each write is a heartbeat.

        Args:
            key: The state key (it need not exist yet: until written, it is stale).
            name: The name it is watched under (default: ``key``).
            warn_after: Seconds without a write that make it ``warn``.
            stale_after: Seconds without a write that make it ``stale``.
            check: Grades each value written: returns a `HealthLevel` (or its
                string), or ``(level, message)``. An exception it raises
                makes the level ``error``.

        Raises:
            ValueError: Nothing to watch (no threshold and no check), a bad
                threshold, or a name already watched.
        """
        if warn_after is None and stale_after is None and check is None:
            msg = f"watch({key!r}) needs warn_after=, stale_after= or check=; give at least one"
            raise ValueError(msg)
        self._add(_Watched(name or key, key, *_thresholds(warn_after, stale_after), check))

    def subsystem(
        self, name: str, *, warn_after: float | None = None, stale_after: float | None = None
    ) -> None:
        """Watch a subsystem that reports through `beat` (it is stale until its first beat).

        Raises:
            ValueError: A bad threshold, or a name already watched.
        """
        self._add(_Watched(name, None, *_thresholds(warn_after, stale_after), None))

    def _add(self, watched: _Watched) -> None:
        name = _name(watched.name)
        if name in self._watched:
            msg = f"{name!r} is watched already; give another name= to watch it twice"
            raise ValueError(msg)
        self._watched[name] = watched
        if self.running:
            self._arm(watched)
            self._publish(watched)

    # -- heartbeats -----------------------------------------------------------------

    def beat(self, name: str, level: HealthLevel | str = HealthLevel.OK, message: str = "") -> None:
        """A heartbeat of subsystem ``name``, with the level and message it reports.

        Raises:
            StateError: ``name`` is not a subsystem of this monitor.
            ValueError: ``level`` is not a `HealthLevel` (or its string).
        """
        watched = self._watched.get(name)
        if watched is None or watched.key is not None:
            known = sorted(n for n, w in self._watched.items() if w.key is None)
            why = f"watches the state key {watched.key!r}" if watched is not None else "is unknown"
            msg = f"beat({name!r}): that name {why}; the subsystems are {known}"
            raise StateError(msg)
        watched.reported = (_level(level), message)
        self._heartbeat(watched)

    def _on_write(self, watched: _Watched, changes: Any) -> None:
        if watched.check is not None:
            watched.reported = _grade(watched.check, changes[watched.key])
        self._heartbeat(watched)

    def _heartbeat(self, watched: _Watched) -> None:
        if not self.running:
            return
        now = self.robot.time()
        watched.last = now
        if watched.fresh[0] is not HealthLevel.OK:
            # Its timer (if any) waits for a later threshold: the first one comes first again.
            watched.fresh = (HealthLevel.OK, "")
            if watched.timer is not None:
                watched.timer.cancel()
                watched.timer = None
        if watched.timer is None:
            self._schedule(watched, now)
        if watched.level() != watched.shown:
            self._publish(watched)

    # -- staleness timers -------------------------------------------------------------

    def _arm(self, watched: _Watched) -> None:
        """Start watching ``watched`` (the monitor runs): subscribe, grade, set its timer."""
        now = self.robot.time()
        state = self.robot.state
        key = watched.key
        if key is not None:
            self._subscriptions.append(
                state.subscribe(lambda changes: self._on_write(watched, changes), keys=key)
            )
            if key in state:
                watched.last = state.timestamp(key)
                if watched.check is not None:
                    watched.reported = _grade(watched.check, state[key])
        watched.fresh = watched.freshness(now)
        self._schedule(watched, now)

    def _schedule(self, watched: _Watched, now: float) -> None:
        deadline = watched.next_deadline(now)
        if deadline is not None:
            loop = asyncio.get_running_loop()
            watched.timer = loop.call_at(deadline, self._due, watched)

    def _due(self, watched: _Watched) -> None:
        watched.timer = None
        now = self.robot.time()
        watched.fresh = watched.freshness(now)
        self._schedule(watched, now)
        if watched.level() != watched.shown:
            self._publish(watched)

    # -- publishing -------------------------------------------------------------------

    def _publish(self, *changed: _Watched) -> None:
        """Publish the new status of ``changed``: the state keys of new levels, then listeners."""
        now = self.robot.time()
        values: dict[str, object] = {}
        for watched in changed:
            level, message = watched.level()
            old = watched.shown
            watched.shown = (level, message)
            if old is None or old[0] is not level:
                watched.since = now
                values[f"{self.prefix}_{watched.name}"] = level.value
                if old is not None:
                    log = _log.warning if _ORDER[level] > _ORDER[old[0]] else _log.info
                    why = f" ({message})" if message else ""
                    log("health of %s: %s -> %s%s", watched.name, old[0], level, why)
        levels = (w.level()[0] for w in self._watched.values())
        overall = max(levels, key=_ORDER.__getitem__, default=HealthLevel.OK)
        if overall is not self._overall:
            self._overall = overall
            values[self.prefix] = overall.value
        if values:
            self.robot.state.update(values)
        for watched in changed:
            self._tell(watched.status())

    def _tell(self, status: HealthStatus) -> None:
        for listener in list(self._listeners):
            try:
                listener(status)
            except Exception:
                _log.exception("health listener %r failed on %s", listener, status)

    # -- reading ----------------------------------------------------------------------

    @property
    def level(self) -> HealthLevel:
        """The worst level of everything watched (``ok`` when nothing is)."""
        return self._overall if self._overall is not None else HealthLevel.OK

    def statuses(self) -> dict[str, HealthStatus]:
        """The status of everything watched, by name (a snapshot; empty until started)."""
        return {n: w.status() for n, w in self._watched.items() if w.shown is not None}

    def subscribe(self, listener: Callable[[HealthStatus], object]) -> Callable[[], None]:
        """Call ``listener(status)`` at each change of a level or message; return an unsubscriber.

        It runs synchronously on the robot's loop: keep it short (queue a
        ``/diagnostics`` message, set an event). An exception in it is logged.
        """
        self._listeners.append(listener)

        def unsubscribe() -> None:
            if listener in self._listeners:
                self._listeners.remove(listener)

        return unsubscribe

    # -- running ----------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """Whether its action runs (between `start` and that action's end)."""
        return self._handle is not None and not self._handle.done()

    def start(self) -> ActionHandle[None]:
        """Start watching: the ``health_monitor`` action, running until cancelled.

        The first levels are written at once (before this returns).

        Raises:
            StateError: It runs already.
            RobotNotRunningError: The robot is not running.
        """
        if self.running:
            msg = f"{self!r} runs already; start it once"
            raise StateError(msg)
        self._handle = handle = _RUN(self.robot, self)
        handle.add_done_callback(self._stop)
        for watched in self._watched.values():
            self._arm(watched)
        self._publish(*self._watched.values())
        return handle

    def _stop(self, handle: ActionHandle[None] | None) -> None:
        """Stop the timers and subscriptions of the run of ``handle`` (once it is over)."""
        if handle is not self._handle:
            return  # an earlier run's late done-callback
        for subscription in self._subscriptions:
            subscription.close()
        self._subscriptions.clear()
        for watched in self._watched.values():
            if watched.timer is not None:
                watched.timer.cancel()
                watched.timer = None

    def __repr__(self) -> str:
        state = "running" if self.running else "stopped"
        return f"<HealthMonitor {self.prefix!r} {state} watching {sorted(self._watched)}>"


async def health_monitor(robot: Robot, monitor: HealthMonitor) -> None:
    """The action of a started `HealthMonitor`: it holds its timers until cancelled."""
    try:
        await asyncio.get_running_loop().create_future()  # until cancelled
    finally:
        monitor._stop(current_action.get())


_RUN = Action(health_monitor)


def _thresholds(warn_after: object, stale_after: object) -> tuple[float | None, float | None]:
    warn = None if warn_after is None else check_seconds("warn_after", warn_after)
    stale = None if stale_after is None else check_seconds("stale_after", stale_after)
    if warn is not None and stale is not None and warn >= stale:
        msg = f"warn_after ({warn!r}) must be shorter than stale_after ({stale!r})"
        raise ValueError(msg)
    return warn, stale


def _name(name: object) -> str:
    if not isinstance(name, str) or not name:
        msg = f"a watched name must be a non-empty string, got {name!r}"
        raise ValueError(msg)
    return name


def _level(level: object) -> HealthLevel:
    if isinstance(level, HealthLevel):
        return level
    if isinstance(level, str) and level in _BY_VALUE:
        return _BY_VALUE[level]
    names = list(_BY_VALUE)
    msg = f"unknown health level {level!r}; use a HealthLevel or one of {names}"
    raise ValueError(msg)


def _grade(check: Callable[[Any], object], value: object) -> tuple[HealthLevel, str]:
    """What ``check`` says of ``value``: ``(level, message)``; ``error`` if it raises."""
    try:
        graded = check(value)
        if isinstance(graded, tuple):
            level, message = graded
            return _level(level), str(message)
        return _level(graded), ""
    except Exception as error:
        _log.exception("health check %r failed on %r", check, value)
        return HealthLevel.ERROR, f"check failed: {error!r}"
