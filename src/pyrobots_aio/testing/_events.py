"""EventLog: an instrument that keeps every executive event, with assertions over them."""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar, overload

from .. import ActionFinished, ActionSpawned, CancelRequested, EventKind, ExecEvent, event_type

if TYPE_CHECKING:
    from collections.abc import Iterator

E = TypeVar("E", bound=ExecEvent)


class EventLog:
    """Keeps the executive events of a robot for assertions in tests.

    Attach it with ``Robot(instruments=[log])`` or ``robot.instruments.add(log)``
    (the plugin's ``robot``/``sim_robot`` fixtures come with one: ``robot_events``).
    Look events up by class (typed: ``log.first(ActionFinished).outcome``) or by
    `EventKind`.

    Examples:
        >>> log = EventLog()
        >>> log.on_event(ActionSpawned(0.0, 1, "walk", parent=None))
        >>> log.names_started(), log.first(ActionSpawned).parent
        (['walk'], None)
    """

    def __init__(self) -> None:
        self.events: list[ExecEvent] = []
        self._names: dict[int, str] = {}

    def on_event(self, event: ExecEvent) -> None:
        """Record one event (the `Instrument` protocol)."""
        if isinstance(event, ActionSpawned) and event.action is not None:
            self._names[event.action] = event.name or ""
        self.events.append(event)

    def __iter__(self) -> Iterator[ExecEvent]:
        return iter(self.events)

    def __len__(self) -> int:
        return len(self.events)

    def name_of(self, action_id: int | None) -> str | None:
        """The name of the action with this id (as spawned), or None."""
        return None if action_id is None else self._names.get(action_id)

    def names_started(self) -> list[str]:
        """The names of every action spawned, in order."""
        return list(self._names.values())

    @overload
    def of_kind(self, kind: type[E], name: str | None = None) -> list[E]: ...
    @overload
    def of_kind(self, kind: EventKind, name: str | None = None) -> list[ExecEvent]: ...
    def of_kind(
        self, kind: type[E] | EventKind, name: str | None = None
    ) -> list[E] | list[ExecEvent]:
        """Every event of ``kind`` (a class, or an `EventKind`) about ``name``."""
        wanted = event_type(kind) if isinstance(kind, EventKind) else kind
        return [
            e for e in self.events if isinstance(e, wanted) and (name is None or e.name == name)
        ]

    @overload
    def first(self, kind: type[E], name: str | None = None, after: float = -1.0) -> E: ...
    @overload
    def first(self, kind: EventKind, name: str | None = None, after: float = -1.0) -> ExecEvent: ...
    def first(
        self, kind: type[E] | EventKind, name: str | None = None, after: float = -1.0
    ) -> E | ExecEvent:
        """The first event of ``kind`` (named ``name``) at or after time ``after``.

        Raises:
            AssertionError: There is none; the message lists what there is.
        """
        for event in self.of_kind(kind, name):
            if event.time >= after:
                return event
        what = kind.value if isinstance(kind, EventKind) else kind.__name__
        seen = sorted({(e.kind.value, e.name) for e in self.events}, key=str)
        msg = f"no {what} event{f' for {name!r}' if name else ''} after t={after}; seen: {seen}"
        raise AssertionError(msg)

    def cancellations(self, victim: str, by: str | None = None) -> list[CancelRequested]:
        """Cancel requests of actions named ``victim`` (made by an action named ``by``)."""
        return [
            e
            for e in self.of_kind(CancelRequested, victim)
            if by is None or self.name_of(e.by) == by
        ]

    def assert_cancelled(
        self, victim: str, *, by: str | None = None, after: float = 0.0, within: float = 1e9
    ) -> CancelRequested:
        """Assert an action named ``victim`` was cancelled (by ``by``) within a time window.

        Example: ``log.assert_cancelled("drive_distance", by="bumper_reflex",
        after=bump.time, within=0.2)`` — the reflex preempted the drive within
        0.2 s of the bump. Returns the cancel event.
        """
        for event in self.cancellations(victim, by):
            if after <= event.time <= after + within:
                return event
        found = [(round(e.time, 6), self.name_of(e.by)) for e in self.cancellations(victim)]
        who = f" by {by!r}" if by else ""
        msg = (
            f"{victim!r} was not cancelled{who} between t={after} and t={after + within}; "
            f"its cancellations (time, by): {found}"
        )
        raise AssertionError(msg)

    def outcomes(self, name: str) -> list[str]:
        """The outcomes of every finished action called ``name``, in order."""
        return [e.outcome for e in self.of_kind(ActionFinished, name)]
