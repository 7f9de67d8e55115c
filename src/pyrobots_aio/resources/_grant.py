"""Requests for resources (`Grant`) and the lock state of one plain resource (`Leaf`).

Each leaf keeps a *stack* of holds, outermost first; every hold's owner is
(or descends from) the owner of the hold below it, because ownership is
inherited: a leaf is free to an owner when nobody holds it or its innermost
holder is that owner or one of its ancestors. Each leaf also keeps a
`WaitQueue` of the requests waiting for it, in service order, and a stack of
`Loan`: the holds set aside while a ``preempt="suspend"`` request borrows it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Generic, Literal, Protocol, TypeAlias, TypeVar

from .._exceptions import LockUsageError
from ._queue import WaitQueue

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

    from ._manager import ResourceManager
    from ._resource import AnyResource, Resource

NEW, WAITING, HELD, RELEASED = range(4)
_STATES = ("new", "waiting", "held", "released")

SUSPEND = "suspend"
"""``preempt=SUSPEND``: pause the holders in the way and borrow their resource."""
Preempt: TypeAlias = bool | Literal["suspend"]
"""How a request treats lower-priority holders: wait (False), cancel (True), or suspend."""
Options: TypeAlias = tuple[bool, int, Preempt]
"""``(wait, priority, preempt)`` of a request."""


class Owner(Protocol):
    """What the manager needs of whoever takes resources (`ActionHandle` fits).

    A public protocol: a stand-in for an action (a test double, another
    executive) implements these and nothing private. The manager never writes
    an owner's state; it asks, and answers what an owner holds and awaits
    (`ResourceManager.held_by`, `ResourceManager.awaited_by`).
    """

    @property
    def id(self) -> int:
        """Its id, for messages and events."""

    @property
    def name(self) -> str:
        """Its name, for messages and events."""

    @property
    def parent(self) -> Owner | None:
        """The owner it descends from; a descendant may take what an ancestor holds."""

    @property
    def cancel_requested(self) -> bool:
        """Whether its cancellation was requested (it is then never suspended)."""

    def cancel(self, reason: str | None = None) -> bool:
        """Request its cancellation (preemption); return False if it is done."""

    def suspend(self, reason: str, by: Owner) -> None:
        """Freeze it and its subtree, apart from any pause, while ``by`` borrows its resource."""

    def unsuspend(self) -> None:
        """End the suspension: it thaws unless it is paused as well."""

    def done(self) -> bool:
        """Whether it is over; its resources are then released."""

    def add_finalizer(self, finalizer: Callable[[], None]) -> None:
        """Call ``finalizer()`` once it has really ended (abandoned: when its task ends)."""


OwnerT = TypeVar("OwnerT", bound=Owner)


def check_options(wait: object, priority: object, preempt: object) -> None:
    """Raise `LockUsageError` unless ``wait`` is a bool, ``priority`` an int, ``preempt`` valid.

    ``preempt`` is True, False or ``"suspend"``.
    """
    if isinstance(priority, bool) or not isinstance(priority, int):
        msg = f"priority must be an int, got {priority!r}; e.g. priority=10 (higher goes first)"
        raise LockUsageError(msg)
    if not isinstance(wait, bool):
        msg = f"wait must be True or False, got {wait!r}"
        raise LockUsageError(msg)
    if not isinstance(preempt, bool) and preempt != SUSPEND:
        msg = f"preempt must be True, False or {SUSPEND!r}, got {preempt!r}"
        raise LockUsageError(msg)


def descends(node: Owner | None, ancestor: Owner) -> bool:
    """Whether ``node`` is ``ancestor`` or one of its descendants."""
    while node is not None:
        if node is ancestor:
            return True
        node = node.parent
    return False


def who(owner: Owner) -> str:
    """``name#id``, as messages name an owner."""
    return f"{owner.name}#{owner.id}"


def holder(owner: Owner) -> str:
    """How a holder is named: ``name#id``, marked if it is done but its task still holds on."""
    if owner.done():  # abandoned by the watchdog: held until its task really ends
        return f"{owner.name}#{owner.id} (abandoned, its task still running)"
    return f"{owner.name}#{owner.id}"


class Grant(Generic[OwnerT]):
    """One request for resources: waiting, then held until released.

    `ResourceManager.acquire` returns it once held; `release` is idempotent.

    Attributes:
        owner: Who asked (an `ActionHandle` on a robot).
        resources: The resources asked for.
        priority: The priority of the request.
    """

    __slots__ = (
        "_future",
        "_manager",
        "_state",
        "bypassed",
        "key",
        "leaves",
        "names",
        "owner",
        "preempt",
        "priority",
        "resources",
        "until_done",
        "wait",
    )

    def __init__(
        self,
        manager: ResourceManager[OwnerT],
        owner: OwnerT,
        resources: tuple[AnyResource, ...],
        leaves: tuple[Leaf[OwnerT], ...],
        options: Options,
        *,
        seq: int,
        rank: float | None = None,
    ) -> None:
        self._manager = manager
        self._state = NEW
        self._future: asyncio.Future[None] | None = None
        self.owner = owner
        self.resources = resources
        self.names = tuple(dict.fromkeys(r.name for r in resources))
        self.leaves = leaves
        self.wait, self.priority = options[0], options[1]
        self.preempt: Preempt = options[2]
        self.key: tuple[float, int] = (-(self.priority if rank is None else rank), seq)
        """Service order: ``(-rank, arrival number)``; the rank is the priority, aged or not."""
        self.until_done = False
        """Held until its owner is done (a ``@lock`` decorator), not for a block or a call."""
        self.bypassed = 0
        """How many later requests were served past it while it waited (see `_rules`)."""

    @property
    def waiting(self) -> bool:
        """Whether the request is still queued."""
        return self._state == WAITING

    @property
    def held(self) -> bool:
        """Whether the resources are held (granted and not yet released)."""
        return self._state == HELD

    def release(self) -> None:
        """Release the resources (does nothing if they are already released)."""
        self._manager.release(self)

    def __repr__(self) -> str:
        names = ", ".join(repr(n) for n in self.names)
        state = _STATES[self._state]
        return f"<Grant {names} {state} by {who(self.owner)} priority={self.priority}>"


class Loan(Generic[OwnerT]):
    """Holds set aside on one leaf while a ``preempt="suspend"`` request borrows it.

    ``holds`` were the top of the leaf's stack, from the outermost holder in
    the borrower's way (the `lender`, suspended with its subtree) up; they go
    back on the stack once the borrower's lineage holds the leaf no more.
    """

    __slots__ = ("borrower", "holds", "leaf", "lender")

    def __init__(
        self, leaf: Leaf[OwnerT], holds: list[Grant[OwnerT]], borrower: Grant[OwnerT]
    ) -> None:
        self.leaf = leaf
        self.holds = holds
        self.borrower = borrower
        self.lender: OwnerT = holds[0].owner
        """The suspended holder: the owner of the outermost hold lent."""


class Leaf(Generic[OwnerT]):
    """The lock state of one plain resource: its holds, its waiting line, its loans."""

    __slots__ = ("compounds", "holds", "lent", "queue", "resource")

    def __init__(self, resource: Resource) -> None:
        self.resource = resource
        self.holds: list[Grant[OwnerT]] = []
        self.queue: WaitQueue[Grant[OwnerT]] = WaitQueue()
        self.compounds = 0
        """How many of the requests in `queue` ask for other leaves too."""
        self.lent: list[Loan[OwnerT]] = []
        """Loans outstanding, oldest first; only the newest can be given back.

        A loan emptied by its (cancelled) lender stays until its borrower
        lets go, so that the loans under it wait for that too.
        """

    def lenders(self) -> list[OwnerT]:
        """The suspended lenders, oldest first (not those whose loans were emptied)."""
        return [loan.lender for loan in self.lent if loan.holds]
