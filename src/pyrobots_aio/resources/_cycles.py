"""Lock cycles: a request that would wait for ever, because what it waits for waits for it.

Compound resources are taken atomically and cannot deadlock, but a program
can still build hold-and-wait itself: nested ``async with lock(A)`` then
``lock(B)`` in one action, ``B`` then ``A`` in another (or ``@lock`` actions
whose children lock the other resource). Before a request waits, the
manager follows the *wait-for* edges from it, and refuses the request
(`ResourceDeadlockError`) if they lead back to its own action.

An edge is drawn only where the wait is certain, so that no working program
is refused:

- a waiting request waits for each hold in its way (a holder that is not
  its owner or an ancestor), unless it would preempt or suspend that holder
  (a lower priority), and unless the holder is being cancelled (its cleanup
  will release);
- a hold is released only once its holder's own waiting requests are
  served; for a hold kept until the holder is done (``@lock`` on the
  action), once its descendants' waiting requests are served too;
- the cycle closes on a hold of the requesting action itself, or of an
  ancestor that keeps it until done (it cannot be done before this action).

A hold of one of the requester's descendants, or an ancestor's ``async
with`` block, may end without this request being served, so it closes no
cycle. Queue order alone never deadlocks (the rules of `_rules` see to
that), so only holds are followed. The search runs only when a request is
about to wait for a busy resource; it visits each hold once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._grant import Grant, OwnerT, descends

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

Step = tuple[OwnerT, str, OwnerT]
"""One wait-for edge: the waiter, the resource it waits for, its holder."""


def find_cycle(
    grant: Grant[OwnerT], waits_of: Callable[[Grant[OwnerT]], Iterable[Grant[OwnerT]]]
) -> list[Step[OwnerT]] | None:
    """The cycle ``grant`` would close by waiting, as steps from its owner; None if there is none.

    ``waits_of(hold)`` gives the waiting requests to serve before ``hold``
    can be released (see the module docstring).
    """
    me = grant.owner
    seen: set[Grant[OwnerT]] = set()
    stack: list[tuple[Grant[OwnerT], list[Step[OwnerT]]]] = [(grant, [])]
    while stack:
        request, path = stack.pop()
        for leaf, hold in _in_way(request):
            step = [*path, (request.owner, leaf, hold.owner)]
            holder = hold.owner
            if holder is me or (hold.until_done and descends(me, holder)):
                return step
            if hold not in seen:
                seen.add(hold)
                stack.extend((waiting, step) for waiting in waits_of(hold))
    return None


def _in_way(request: Grant[OwnerT]) -> list[tuple[str, Grant[OwnerT]]]:
    """The holds ``request`` certainly waits for, with the name of the resource each holds."""
    owner, found = request.owner, []
    for leaf in request.leaves:
        for hold in leaf.holds:
            holder = hold.owner
            if descends(owner, holder) or holder.cancel_requested:
                continue
            if request.preempt and hold.priority < request.priority:
                continue  # it would preempt or suspend that holder
            found.append((leaf.resource.name, hold))
    return found
