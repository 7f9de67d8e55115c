"""Suspend instead of cancel: lending a held resource to a ``preempt="suspend"`` request.

A suspending request is served, when everything in its way is holders of a
lower priority, by *borrowing* their leaves: on each leaf, the holds from the
outermost one in its way up are set aside as a `Loan`, their outermost owner
(the *lender*) is suspended with its subtree (frozen as by a pause, its pause
hooks park its actuators), and the request is granted at once. When the
borrower's lineage holds the leaf no more (released, done, any outcome), the
newest loan goes back on the leaf before anyone in line is served, and once
a lender has no loan left it resumes where it stood.

Semantics where the design leaves a choice:

- Nested: a borrower may itself be suspended by a higher-priority suspending
  request; loans stack per leaf and are given back newest first.
- A lender cancelled while suspended thaws at once (cancellation reaches a
  frozen action) and its cleanup runs, without the lent leaf: the loan is
  forfeited, and when the borrower lets go the leaf goes to the waiting line
  as if released (its cleanup asks again like anyone else). Its grant still
  counts as held (`ResourceManager.held_by`) until it ends. A lender that
  was itself a borrower (nested) and releases all it was lent ends its
  suspension, but its emptied loan stays on the stack until its borrower
  lets go: the loans under it go back only then, never while the leaf is
  lent onward.
- A holder already paused is suspended as well, apart from its pause: at the
  end of the loan it stays paused until ``resume()``; ``resume()`` during the
  loan lifts the pause only, never the suspension.
- A borrower that never lets go keeps the lender suspended: the suspension
  ends when the borrower ends, whatever its outcome, or when the lender is
  cancelled (``robot.emergency_stop`` cancels both).
- Nobody is suspended when a holder in the way (or a descendant of it
  holding the leaf) is being cancelled or is done but still running
  (abandoned): its cleanup runs unfrozen and may still drive the resource,
  so the request waits for it like a ``preempt=True`` one, and suspends
  whoever is in the way once it is gone. Nor when a request queued ahead must
  be served first: it waits in line (``wait=False``: it is skipped).
- A ``preempt=True`` request or the emergency stop that cancels a borrower
  cancels its lenders too (if their priority is lower), else they would get
  the resource back first.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Generic

from . import _rules
from ._grant import Loan, Owner, OwnerT, descends

if TYPE_CHECKING:
    from ._grant import Grant, Leaf

Plan = list[tuple["Leaf[OwnerT]", int]]
"""Where a request borrows: each leaf in its way, with the index of its outermost hold there."""


def plan(grant: Grant[OwnerT]) -> Plan[OwnerT] | None:
    """Where ``grant`` would borrow, or None if it may not suspend the holders now."""
    found: Plan[OwnerT] = []
    owner, priority = grant.owner, grant.priority
    for leaf in grant.leaves:
        holds = leaf.holds
        first = next((i for i, h in enumerate(holds) if not descends(owner, h.owner)), None)
        if first is None:
            continue
        lender = holds[first].owner
        for hold in holds[first:]:
            if hold.priority >= priority or _unfreezable(hold.owner, lender):
                return None
        found.append((leaf, first))
    if not found or _rules.queued_ahead(grant) is not None:
        return None
    return found


def _unfreezable(node: Owner, lender: Owner) -> bool:
    """Whether ``node`` (under ``lender``) would run on through a suspension of ``lender``."""
    current: Owner | None = node
    while current is not None:
        if current.done() or current.cancel_requested:
            return True
        if current is lender:
            return False
        current = current.parent
    return False


class Loans(Generic[OwnerT]):
    """The loans of one manager: how many each lender has outstanding."""

    __slots__ = ("count",)

    def __init__(self) -> None:
        self.count: dict[OwnerT, int] = {}

    def lend(self, grant: Grant[OwnerT], where: Plan[OwnerT]) -> list[Loan[OwnerT]]:
        """Set aside the holds in ``grant``'s way (per ``where``); return the new loans."""
        made = []
        for leaf, first in where:
            loan = Loan(leaf, leaf.holds[first:], grant)
            del leaf.holds[first:]
            leaf.lent.append(loan)
            self.count[loan.lender] = self.count.get(loan.lender, 0) + 1
            made.append(loan)
        return made

    def unhold(self, leaf: Leaf[OwnerT], grant: Grant[OwnerT]) -> OwnerT | None:
        """Take ``grant`` off ``leaf`` (held or lent); return a lender whose last loan ended."""
        holds = leaf.holds
        if grant in holds:
            holds.remove(grant)
            return None
        for loan in leaf.lent:
            if grant in loan.holds:
                loan.holds.remove(grant)
                # Everything lent was released: nothing to give back, but the
                # loan stays on the stack while its borrower holds the leaf,
                # or the loans under it would go back while it is lent onward.
                return None if loan.holds else self._ended(loan)
        return None  # a forfeited loan's hold

    def give_back(self, leaf: Leaf[OwnerT]) -> list[tuple[Loan[OwnerT], bool, OwnerT | None]]:
        """Give back every loan on ``leaf`` that may go back now, newest first.

        Returns, for each loan ended, whether it was given back (False:
        forfeited by a cancelled lender) and the lender to resume (None if it
        still has other loans out).
        """
        ended = []
        holds = leaf.holds
        while leaf.lent:
            loan = leaf.lent[-1]
            borrower = loan.borrower.owner
            if any(descends(hold.owner, borrower) for hold in holds):
                break
            leaf.lent.pop()
            if not loan.holds:  # emptied and ended by `unhold`
                continue
            lender = loan.lender
            restored = not (lender.done() or lender.cancel_requested)
            if restored:
                holds.extend(loan.holds)
            ended.append((loan, restored, self._ended(loan)))
        return ended

    def _ended(self, loan: Loan[OwnerT]) -> OwnerT | None:
        lender = loan.lender
        left = self.count[lender] - 1
        if left:
            self.count[lender] = left
            return None
        del self.count[lender]
        return lender
