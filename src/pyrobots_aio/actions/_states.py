"""How an action ended (`Outcome`) and where it is in its life (`ActionState`)."""

from __future__ import annotations

import enum


class Outcome(enum.Enum):
    """How an action ended; ``NOT_DONE`` while it is pending, waiting or running."""

    NOT_DONE = "not_done"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
    SKIPPED = "skipped"


class ActionState(enum.Enum):
    """Where an action is in its life, as `ActionInfo.state` reports it.

    The handle keeps its phase as one of these too: `PENDING`, `RUNNING`,
    `FINISHING` or `DONE`; the others are read from the running phase
    (a cancellation requested, a frozen spell, a resource awaited).
    """

    PENDING = "pending"
    """Started, its task not yet scheduled."""
    WAITING = "waiting"
    """Waiting for a resource."""
    RUNNING = "running"
    CANCELLING = "cancelling"
    """Cancellation requested; its cleanup is running."""
    PAUSED = "paused"
    """Frozen where it stands: it or an ancestor was paused (`ActionHandle.pause`).

    Or suspended: a ``@lock(..., preempt="suspend")`` request borrows its resource.
    """
    FINISHING = "finishing"
    """Its body has ended; its children are being cancelled and awaited."""
    DONE = "done"
