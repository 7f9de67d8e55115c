"""The arbitration rules: when a request may be served, and whom it must let go first.

A request is served only when every leaf it asks for is free to its owner,
all at once: nobody ever holds some leaves while waiting for others (no
hold-and-wait, hence no deadlock whatever the order of declaration).

A request never overtakes a request ahead of it in service order (higher
priority, or equal priority and earlier) that wants one of its leaves, so
compound requests are not starved. One exception keeps inheritance
deadlock-free: a request need not yield to a queued request that is blocked
by the requester's own lineage (the parent holding the wheels must not wait
for its child, which would wait behind someone who waits for the parent).
That check looks at the holds directly in the way; hold-and-wait that a
program builds itself (nested ``async with lock`` in opposite orders) can
still deadlock, as with any lock.

These are pure functions of the lock state; ``below`` maps each owner to the
number of queued requests of it and its descendants.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeAlias

from ._grant import Grant, Leaf, Owner, OwnerT, descends

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ._resource import Resource

Obstacle: TypeAlias = "tuple[Resource, OwnerT | None, Grant[OwnerT] | None]"
"""What stops a request: a resource, its holder in the way, the request queued ahead."""


def grantable(grant: Grant[OwnerT], below: Mapping[Owner, int]) -> bool:
    """Whether ``grant`` may be served now."""
    for leaf in grant.leaves:
        if holder_in_way(grant, leaf) is not None:
            return False
    return all(clear_ahead(grant, leaf, below) for leaf in grant.leaves if leaf.queue)


def clear_ahead(grant: Grant[OwnerT], leaf: Leaf[OwnerT], below: Mapping[Owner, int]) -> bool:
    """Whether no request ahead of ``grant`` in ``leaf``'s line must be served first."""
    return first_ahead(grant, leaf, below) is None


def first_ahead(
    grant: Grant[OwnerT], leaf: Leaf[OwnerT], below: Mapping[Owner, int]
) -> Grant[OwnerT] | None:
    """The request ahead of ``grant`` in ``leaf``'s line that must be served first, or None.

    Only for a leaf that is free to ``grant``'s owner (nobody else holds it).
    """
    holds = leaf.holds
    if holds:  # inherited: everyone else in line is blocked by the lineage, bar its descendants
        others = below.get(holds[-1].owner, 0) - grant.waiting
        if others <= 0:
            return None
    return _yields_to(grant, leaf)


def _yields_to(grant: Grant[OwnerT], leaf: Leaf[OwnerT]) -> Grant[OwnerT] | None:
    """The first request ahead of ``grant`` in ``leaf``'s line that it must let go first."""
    owner, key = grant.owner, grant.key
    for other in leaf.queue:
        if other is grant or other.key > key:
            return None
        if not exempt(owner, other):
            return other
    return None


def exempt(owner: Owner, other: Grant[OwnerT]) -> bool:
    """Whether ``other`` is blocked by ``owner``'s lineage (so ``owner`` need not yield)."""
    for leaf in other.leaves:
        for hold in leaf.holds:
            if not descends(other.owner, hold.owner):
                if descends(owner, hold.owner):
                    return True
                break
    return False


def may_exempt(grant: Grant[OwnerT], below: Mapping[Owner, int]) -> bool:
    """Whether some request behind ``grant`` might be exempt from yielding to it."""
    if not below:
        return False
    for leaf in grant.leaves:
        for hold in leaf.holds:
            if below.get(hold.owner) and not descends(grant.owner, hold.owner):
                return True
    return False


def blockers(grant: Grant[OwnerT]) -> list[tuple[Grant[OwnerT], Leaf[OwnerT]]]:
    """The holds in ``grant``'s way, each with the leaf it blocks.

    Holds lent to a ``preempt="suspend"`` request count: they come back first.
    """
    owner = grant.owner
    return [
        (hold, leaf)
        for leaf in grant.leaves
        for hold in (*leaf.holds, *(h for loan in leaf.lent for h in loan.holds))
        if not descends(owner, hold.owner)
    ]


def queued_ahead(grant: Grant[OwnerT]) -> tuple[Leaf[OwnerT], Grant[OwnerT]] | None:
    """A request queued ahead of ``grant`` that it must let go first, whoever holds now.

    A request that preempts without waiting asks this before cancelling anyone:
    once the holders are gone, such a request would be served first.
    """
    for leaf in grant.leaves:
        if leaf.queue:
            other = _yields_to(grant, leaf)
            if other is not None:
                return leaf, other
    return None


def holder_in_way(grant: Grant[OwnerT], leaf: Leaf[OwnerT]) -> OwnerT | None:
    """The innermost holder of ``leaf`` if it is not ``grant``'s owner or an ancestor, else None."""
    holds = leaf.holds
    if holds and not descends(grant.owner, holds[-1].owner):
        return holds[-1].owner
    return None


def obstacle(grant: Grant[OwnerT], below: Mapping[Owner, int]) -> Obstacle[OwnerT]:
    """What stops a request that cannot be served: a leaf, its holder, the request ahead.

    The first busy leaf and its holder (no request ahead reported); else the
    first leaf that is free but promised to a request ahead, with that request
    (the holder is then None).
    """
    for leaf in grant.leaves:
        holder = holder_in_way(grant, leaf)
        if holder is not None:
            return leaf.resource, holder, None
    for leaf in grant.leaves:
        if leaf.queue:
            other = first_ahead(grant, leaf, below)
            if other is not None:
                return leaf.resource, None, other
    return grant.leaves[0].resource, None, None
