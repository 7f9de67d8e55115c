"""ActionInfo: a snapshot of one running action, and the printable action tree."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Iterable

    from ._handle import ActionHandle
    from ._states import ActionState


_UNREAD = object()


@dataclass(frozen=True, slots=True)
class ActionInfo:
    """What one action is doing at the moment the snapshot was taken.

    Only what changes is copied (the state, the resources, the reason): a
    snapshot costs well under a microsecond, so ``robot.running()`` stays cheap
    with thousands of actions. The location is read from the coroutine's
    await chain when first asked.

    Attributes:
        id: The action's id (unique within its robot).
        name: The action's name (its function's name).
        parent: The parent action's id, or None in the root scope.
        state: Pending, waiting, running, cancelling, finishing or done.
        started_at: Loop time when its body started, or None if pending.
        held: Names of the resources it holds.
        awaiting: Names of the resources it waits for.
        cancel_reason: The reason of a requested cancellation, or None.
        location: ``file:line`` where its body is suspended, or None.
    """

    handle: ActionHandle[Any] = field(repr=False)
    state: ActionState
    started_at: float | None
    held: tuple[str, ...]
    awaiting: tuple[str, ...]
    cancel_reason: str | None
    _where: object = field(default=_UNREAD, init=False, repr=False, compare=False)

    @classmethod
    def of(cls, handle: ActionHandle[Any]) -> ActionInfo:
        """Take a snapshot of ``handle`` (its location is read when first asked)."""
        # The fields go straight into their slots: a frozen dataclass's __init__ sets each
        # through object.__setattr__, which made this twice as slow (robot.running() takes
        # a snapshot of every running action).
        held, awaiting = handle._executive.resources.holdings(handle)
        info = _new(cls)
        _set_handle(info, handle)
        _set_state(info, handle._state(bool(awaiting)))
        _set_started_at(info, handle.started_at)
        _set_held(info, held)
        _set_awaiting(info, awaiting)
        _set_cancel_reason(info, handle.cancel_reason)
        _set_where(info, _UNREAD)
        return info

    @property
    def id(self) -> int:
        """The action's id (unique within its robot)."""
        return self.handle.id

    @property
    def name(self) -> str:
        """The action's name."""
        return self.handle.name

    @property
    def parent(self) -> int | None:
        """The parent action's id, or None in the root scope."""
        parent = self.handle.parent
        return None if parent is None else parent.id

    @property
    def location(self) -> str | None:
        """``file:line`` where the body was suspended when first asked, or None."""
        where = self._where
        if where is _UNREAD:
            where = self.handle.location()
            object.__setattr__(self, "_where", where)
        return where  # type: ignore[return-value]

    def __repr__(self) -> str:
        return f"<ActionInfo {self.describe()}>"

    def describe(self) -> str:
        """One line: ``name#id state [holds ...] [waits for ...] at file:line``."""
        parts = [f"{self.name}#{self.id}", self.state.value]
        if self.held:
            parts.append(f"holds {', '.join(self.held)}")
        if self.awaiting:
            parts.append(f"waits for {', '.join(self.awaiting)}")
        if self.location:
            parts.append(f"at {self.location}")
        return " ".join(parts)


_new = object.__new__
(
    _set_handle,
    _set_state,
    _set_started_at,
    _set_held,
    _set_awaiting,
    _set_cancel_reason,
    _set_where,
) = (
    ActionInfo.__dict__[name].__set__
    for name in ("handle", "state", "started_at", "held", "awaiting", "cancel_reason", "_where")
)


def render_tree(roots: Iterable[ActionHandle[Any]]) -> str:
    """Draw the running actions as an indented tree, one line per action."""
    lines: list[str] = []
    stack = [(root, 0) for root in reversed(list(roots))]
    while stack:
        handle, depth = stack.pop()
        lines.append("  " * depth + ActionInfo.of(handle).describe())
        stack.extend((child, depth + 1) for child in reversed(handle.children))
    return "\n".join(lines) if lines else "(no running actions)"
