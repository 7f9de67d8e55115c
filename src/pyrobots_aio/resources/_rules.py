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

from typing import TYPE_CHECKING

from ._grant import Grant, Leaf, Owner, OwnerT, descends

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ._resource import Resource


def grantable(grant: Grant[OwnerT], below: Mapping[Owner, int]) -> bool:
    """Whether ``grant`` may be served now."""
    owner = grant.owner
    for leaf in grant.leaves:
        holds = leaf.holds
        if holds and not descends(owner, holds[-1].owner):
            return False
    return all(clear_ahead(grant, leaf, below) for leaf in grant.leaves if leaf.queue)


def clear_ahead(grant: Grant[OwnerT], leaf: Leaf[OwnerT], below: Mapping[Owner, int]) -> bool:
    """Whether no request ahead of ``grant`` in ``leaf``'s line must be served first."""
    holds = leaf.holds
    if holds:  # inherited: everyone else in line is blocked by the lineage, bar its descendants
        others = below.get(holds[-1].owner, 0) - grant.waiting
        if others <= 0:
            return True
    owner, key = grant.owner, grant.key
    for other in leaf.queue:
        if other is grant or other.key > key:
            return True
        if not exempt(owner, other):
            return False
    return True


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
    """The holds in ``grant``'s way, each with the leaf it blocks."""
    owner = grant.owner
    return [
        (hold, leaf)
        for leaf in grant.leaves
        for hold in leaf.holds
        if not descends(owner, hold.owner)
    ]


def obstacle(grant: Grant[OwnerT], below: Mapping[Owner, int]) -> tuple[Resource, OwnerT | None]:
    """The first busy leaf of a request that cannot be served, and its holder.

    The holder is None when the leaf is free but promised to a request ahead.
    """
    owner = grant.owner
    for leaf in grant.leaves:
        if leaf.holds and not descends(owner, leaf.holds[-1].owner):
            return leaf.resource, leaf.holds[-1].owner
    for leaf in grant.leaves:
        if leaf.queue and not clear_ahead(grant, leaf, below):
            return leaf.resource, None
    return grant.leaves[0].resource, None
