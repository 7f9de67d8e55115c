"""The arbitration rules: when a request may be served, and whom it must let go first.

A request is served only when every leaf it asks for is free to its owner,
all at once: nobody ever holds some leaves while waiting for others (no
hold-and-wait, hence no deadlock whatever the order of declaration).

A request never overtakes a request ahead of it in service order (higher
rank, or equal rank and earlier) that wants one of its leaves and could be
served as soon as it is free, so compound requests are not starved. Two
exceptions:

- Inheritance stays deadlock-free: a request need not yield to a queued
  request that is blocked by the requester's own lineage (the parent holding
  the wheels must not wait for its child, which would wait behind someone
  who waits for the parent).
- No head-of-line blocking, bounded: a request need not yield to a queued
  request that is *held up* (a holder stands in its way, so it cannot run
  now whatever happens to its other leaves) and that has been passed fewer
  than `BYPASS_LIMIT` times (and it passes at most `LOOKAHEAD` of them on
  one leaf, which bounds the cost of every hand-off). A request that can run now uses those leaves
  instead of leaving them idle; once a request has been passed
  `BYPASS_LIMIT` times it keeps its place against everyone after it, so it
  waits at most that many extra holds and is never starved.

These checks look at the holds directly in the way; hold-and-wait that a
program builds itself (nested ``async with lock`` in opposite orders) is
refused by `_cycles` when the request that would close the cycle is made.

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


def _yields_to(
    grant: Grant[OwnerT], leaf: Leaf[OwnerT], *, skip_held_up: bool = True
) -> Grant[OwnerT] | None:
    """The first request ahead of ``grant`` in ``leaf``'s line that it must let go first.

    With ``skip_held_up`` False, held-up requests count too: a request that
    removes the holders in its way (preempting, suspending) may free them.
    """
    owner, key = grant.owner, grant.key
    passes = LOOKAHEAD if skip_held_up else 0
    for other in leaf.queue:
        if other is grant or other.key > key:
            return None
        if exempt(owner, other):
            continue
        if passes and held_up(other):
            passes -= 1
            continue
        return other
    return None


BYPASS_LIMIT = 16
"""How many later requests may be served past a held-up request before it keeps its place.

Measured (``python -m tests.bench resources``: 24 actions, 6 resources, random
compounds, 600 virtual seconds): no passing (DESIGN §4's strict order) kept
the resources 56 % busy; 16 passes, 73 % (77 % with aging), for a longest
wait of the lowest priority of 99 s instead of 72 s (31 s instead of 28 s with
aging); unbounded passing, 81 % but 224 s.
"""


LOOKAHEAD = 16
"""How many held-up requests a request may pass on one leaf's line (it bounds every scan)."""


def held_up(grant: Grant[OwnerT]) -> bool:
    """Whether later requests may pass ``grant``: a holder is in its way, and passes are left.

    Such a request cannot run before that holder lets go, whatever happens
    to its other leaves.
    """
    if grant.bypassed >= BYPASS_LIMIT:
        return False
    return any(holder_in_way(grant, leaf) is not None for leaf in grant.leaves)


def bypassed(grant: Grant[OwnerT]) -> set[Grant[OwnerT]]:
    """The queued requests ahead of ``grant`` that it passes (asked before it holds)."""
    owner, key = grant.owner, grant.key
    passed = set()
    for leaf in grant.leaves:
        for other in leaf.queue:
            if other.key > key:
                break
            if other is not grant and not exempt(owner, other):
                passed.add(other)
    return passed


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

    A request that preempts without waiting, or suspends, asks this before
    cancelling or suspending anyone: once the holders are gone, such a request
    would be served first (held-up requests count: the holders that hold them
    up may be the ones removed).
    """
    for leaf in grant.leaves:
        if leaf.queue:
            other = _yields_to(grant, leaf, skip_held_up=False)
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
