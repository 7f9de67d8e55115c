"""ActionInfo: a snapshot of one running action, and the printable action tree."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Iterable

    from ._handle import ActionHandle, ActionState


@dataclass(frozen=True, slots=True)
class ActionInfo:
    """What one action is doing at the moment the snapshot was taken.

    Attributes:
        id: The action's id (unique within its robot).
        name: The action's name (its function's name).
        parent: The parent action's id, or None in the root scope.
        state: Pending, waiting, running, cancelling, finishing or done.
        started_at: Loop time when its body started, or None if pending.
        location: ``file:line`` where its body is suspended, or None.
        held: Names of the resources it holds.
        awaiting: Names of the resources it waits for.
        cancel_reason: The reason of a requested cancellation, or None.
    """

    id: int
    name: str
    parent: int | None
    state: ActionState
    started_at: float | None
    location: str | None
    held: tuple[str, ...]
    awaiting: tuple[str, ...]
    cancel_reason: str | None

    @classmethod
    def of(cls, handle: ActionHandle[Any]) -> ActionInfo:
        """Take a snapshot of ``handle``."""
        return cls(
            id=handle.id,
            name=handle.name,
            parent=handle.parent.id if handle.parent is not None else None,
            state=handle.state,
            started_at=handle.started_at,
            location=handle.location(),
            held=handle.held,
            awaiting=handle.awaiting,
            cancel_reason=handle.cancel_reason,
        )

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


def render_tree(roots: Iterable[ActionHandle[Any]]) -> str:
    """Draw the running actions as an indented tree, one line per action."""
    lines: list[str] = []
    stack = [(root, 0) for root in reversed(list(roots))]
    while stack:
        handle, depth = stack.pop()
        lines.append("  " * depth + ActionInfo.of(handle).describe())
        stack.extend((child, depth + 1) for child in reversed(handle.children))
    return "\n".join(lines) if lines else "(no running actions)"
