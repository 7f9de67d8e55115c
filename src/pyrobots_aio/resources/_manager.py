"""ResourceManager: the lock state of one robot (``robot.resources``).

The manager keeps, for each plain resource it has seen, a `Leaf` (holds and
waiting line) and applies the rules of `_rules`. A hand-off is served by
scanning the lines of the leaves whose state changed, from the front, and
granting every request that can now proceed; a scan stops at the first
request that cannot, since everything behind it on that leaf yields to it.
Only when some descendant of a blocking holder waits (an exemption might
apply) does a scan go past it. Granted waiters are woken through their own
future: no thundering herd, no polling, and a hand-off costs the same with
one waiter or a thousand. Lending to ``preempt="suspend"`` requests is in
`_loans` (its docstring gives the semantics).
"""

from __future__ import annotations

import asyncio
import functools
import logging
from typing import TYPE_CHECKING, Generic, NoReturn

from .._core._instrument import EventKind, ExecEvent, Instruments
from .._exceptions import ActionSkipped, LockUsageError
from . import _loans, _rules
from ._grant import (
    HELD,
    RELEASED,
    SUSPEND,
    WAITING,
    Grant,
    Leaf,
    Options,
    Owner,
    OwnerT,
    Preempt,
    check_options,
    holder,
    who,
)
from ._resource import AnyResource, Resource, check_resource

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

_log = logging.getLogger("pyrobots_aio.resources")


class _Record(Generic[OwnerT]):
    """The grants and waiting requests of one owner."""

    __slots__ = ("grants", "waiting")

    def __init__(self) -> None:
        self.grants: list[Grant[OwnerT]] = []
        self.waiting: list[Grant[OwnerT]] = []


def _names(grants: list[Grant[OwnerT]]) -> tuple[str, ...]:
    """The names of the resources of ``grants``, each once, in order."""
    if len(grants) == 1:
        return grants[0].names
    return tuple(dict.fromkeys(name for grant in grants for name in grant.names))


def _loop_time() -> float:
    return asyncio.get_running_loop().time()


class ResourceManager(Generic[OwnerT]):
    """The lock state of one robot (``robot.resources``): who holds what, who waits.

    Args:
        instruments: Where resource events go (waiting, acquired, released,
            preempted, skipped).
        clock: The time stamp of those events; the running loop's clock by default.

    Example:
        >>> import asyncio
        >>> from pyrobots_aio import Robot, action
        >>> from pyrobots_aio.actions import lock
        >>> from pyrobots_aio.resources import Resource
        >>> WHEELS = Resource("wheels")
        >>> @action
        ... @lock(WHEELS)
        ... async def drive(robot: Robot) -> str:
        ...     return repr(robot.resources)
        >>> async def main() -> str:
        ...     async with Robot() as robot:
        ...         return await drive(robot)
        >>> asyncio.run(main())
        "<ResourceManager 'wheels' held by drive#1>"
    """

    def __init__(
        self, instruments: Instruments | None = None, *, clock: Callable[[], float] | None = None
    ) -> None:
        self._instruments = instruments if instruments is not None else Instruments()
        self._clock = clock if clock is not None else _loop_time
        self._leaves: dict[str, Leaf[OwnerT]] = {}
        self._owners: dict[OwnerT, _Record[OwnerT]] = {}
        self._below: dict[Owner, int] = {}
        """For every owner, how many queued requests it or its descendants have."""
        self._seq = 0
        self._work: list[Leaf[OwnerT]] = []
        self._marked: set[Grant[OwnerT]] = set()
        self._flushing = False
        self._loans: _loans.Loans[OwnerT] = _loans.Loans()

    # -- taking and giving back -------------------------------------------

    async def acquire(
        self,
        owner: OwnerT,
        *resources: AnyResource,
        wait: bool = True,
        priority: int = 0,
        preempt: Preempt = False,
    ) -> Grant[OwnerT]:
        """Take every leaf of ``resources`` at once for ``owner``, waiting if need be.

        Args:
            owner: Who takes them (an `ActionHandle`).
            *resources: Plain or compound resources, taken in one atomic request.
            wait: If False, raise `ActionSkipped` instead of waiting.
            priority: Higher priorities are served first.
            preempt: Cancel the holders in the way if all have a lower priority,
                then wait until they are done, behind any earlier queued request
                of equal or higher priority (with ``wait`` False: only if there
                is none, else skip without cancelling anyone). ``"suspend"``:
                suspend them instead and borrow their resources at once, as
                soon as nothing queued ahead must go first; they get them back,
                and resume, when ``owner`` lets go (see `_loans`).

        Returns:
            The `Grant`, held; call its ``release()`` when done.

        Raises:
            ActionSkipped: ``wait`` is False and a resource is busy (or promised
                to an earlier request); it names the holder or that request.
            InvalidResourceError: Something given is not a resource.
            LockUsageError: Bad options, no resources, or ``owner`` is done.
        """
        grant = self._request(owner, resources, (wait, priority, preempt))
        if _rules.grantable(grant, self._below):
            self._grant(grant)
            return grant
        if preempt == SUSPEND:
            if self._lend(grant):
                return grant
            preempting = False
        else:
            preempting = preempt and self._preempt(grant)
        if not wait and not preempting:
            self._skip(grant)
        return await self._wait(grant)

    def release(self, grant: Grant[OwnerT]) -> None:
        """Release ``grant`` and serve whoever can now proceed (idempotent)."""
        if grant._state == WAITING:
            self._withdraw(grant)
        if grant._state != HELD:
            return
        grant._state = RELEASED
        lent = False
        for leaf in grant.leaves:
            if leaf.lent:
                lent = True
                self._unhold(leaf, grant)
            elif grant in leaf.holds:  # else a forfeited loan's
                leaf.holds.remove(grant)
        record = self._owners.get(grant.owner)
        if record is not None:
            record.grants.remove(grant)
            self._sync(grant.owner, record)
        if self._instruments:
            self._emit(EventKind.RESOURCE_RELEASED, grant)
        if lent:
            self._give_back(grant.leaves)
        self._flush(grant.leaves)

    # -- introspection ----------------------------------------------------

    def owner(self, resource: AnyResource) -> OwnerT | None:
        """The action holding ``resource`` (its first held leaf, for a compound), or None.

        With inherited ownership this is the innermost holder: the descendant
        now using what its ancestor locked.
        """
        for leaf in check_resource(resource, "the resource to look up").leaves:
            state = self._leaves.get(leaf.name)
            if state is not None and state.holds:
                return state.holds[-1].owner
        return None

    def waiters(self, resource: AnyResource) -> list[OwnerT]:
        """The owners waiting for ``resource`` (any of its leaves), in service order."""
        found: dict[Grant[OwnerT], None] = {}
        for leaf in check_resource(resource, "the resource to look up").leaves:
            state = self._leaves.get(leaf.name)
            if state is not None:
                found.update(dict.fromkeys(state.queue))
        ordered = sorted(found, key=lambda grant: grant.key)
        return list(dict.fromkeys(grant.owner for grant in ordered))

    def lenders(self, resource: AnyResource) -> list[OwnerT]:
        """The holders suspended while ``resource`` (any of its leaves) is lent, oldest first.

        A ``preempt="suspend"`` request borrowed it from them; they get it back
        and resume when it lets go.
        """
        found: dict[OwnerT, None] = {}
        for leaf in check_resource(resource, "the resource to look up").leaves:
            state = self._leaves.get(leaf.name)
            if state is not None:
                found.update(dict.fromkeys(loan.lender for loan in state.lent))
        return list(found)

    def held(self) -> dict[Resource, OwnerT]:
        """Every plain resource held now, and its (innermost) holder."""
        return {s.resource: s.holds[-1].owner for s in self._leaves.values() if s.holds}

    def __repr__(self) -> str:
        parts = [self._describe(s) for s in self._leaves.values() if s.holds or s.queue]
        return f"<ResourceManager {'; '.join(parts) if parts else 'idle'}>"

    @staticmethod
    def _describe(state: Leaf[OwnerT]) -> str:
        what = f"held by {holder(state.holds[-1].owner)}" if state.holds else "free"
        if state.lent:
            what += f" (lent by {', '.join(who(loan.lender) for loan in state.lent)})"
        queued = [who(grant.owner) for grant in state.queue]
        if queued:
            more = f" and {len(queued) - 5} more" if len(queued) > 5 else ""
            what += f", waiters [{', '.join(queued[:5])}{more}]"
        return f"{state.resource.name!r} {what}"

    # -- requests ---------------------------------------------------------

    def _request(
        self, owner: OwnerT, resources: tuple[AnyResource, ...], options: Options
    ) -> Grant[OwnerT]:
        check_options(*options)
        if not resources:
            msg = f"{who(owner)} asked for no resource; name at least one to acquire"
            raise LockUsageError(msg)
        for resource in resources:
            check_resource(resource, "a resource to acquire")
        if owner.done():
            names = [r.name for r in resources]
            msg = f"{who(owner)} is done; it cannot take {names} any more"
            raise LockUsageError(msg)
        leaves = dict.fromkeys(self._leaf(leaf) for r in resources for leaf in r.leaves)
        self._seq += 1
        return Grant(self, owner, resources, tuple(leaves), options, seq=self._seq)

    def _leaf(self, resource: Resource) -> Leaf[OwnerT]:
        state = self._leaves.get(resource.name)
        if state is None:
            state = self._leaves[resource.name] = Leaf(resource)
        return state

    def _record(self, owner: OwnerT) -> _Record[OwnerT]:
        record = self._owners.get(owner)
        if record is None:
            record = self._owners[owner] = _Record()
            owner.add_finalizer(functools.partial(self._owner_done, owner))
        return record

    async def _wait(self, grant: Grant[OwnerT]) -> Grant[OwnerT]:
        grant._state = WAITING
        owner = grant.owner
        record = self._record(owner)
        record.waiting.append(grant)
        for leaf in grant.leaves:
            leaf.queue.add(grant)
        self._count_below(owner, 1)
        self._sync(owner, record)
        if self._instruments:
            self._emit(EventKind.RESOURCE_WAITING, grant)
        future = grant._future = asyncio.get_running_loop().create_future()
        try:
            await future
        except BaseException:  # cancelled (or the owner ended): leave the line, then re-raise
            self._withdraw(grant)
            raise
        return grant

    def _withdraw(self, grant: Grant[OwnerT]) -> None:
        """Take a waiting request out of line, or release it if it was granted meanwhile."""
        if grant._state == HELD:
            self.release(grant)
            return
        if grant._state != WAITING:
            return
        grant._state = RELEASED
        for leaf in grant.leaves:
            leaf.queue.discard(grant)
        self._count_below(grant.owner, -1)
        record = self._owners.get(grant.owner)
        if record is not None:
            record.waiting.remove(grant)
            self._sync(grant.owner, record)
        if self._instruments:
            self._emit(EventKind.RESOURCE_RELEASED, grant, withdrawn=True)
        self._flush(grant.leaves)

    def _grant(self, grant: Grant[OwnerT]) -> None:
        waited = grant._state == WAITING
        grant._state = HELD
        owner = grant.owner
        record = self._record(owner)
        for leaf in grant.leaves:
            if waited:
                leaf.queue.discard(grant)
            leaf.holds.append(grant)
        if waited:
            record.waiting.remove(grant)
            self._count_below(owner, -1)
            if grant._future is not None and not grant._future.done():
                grant._future.set_result(None)
        record.grants.append(grant)
        self._sync(owner, record)
        if self._instruments:
            self._emit(EventKind.RESOURCE_ACQUIRED, grant)
        self._flush(grant.leaves)

    def _owner_done(self, owner: OwnerT) -> None:
        """Safety net: an owner that is done holds and awaits nothing."""
        record = self._owners.pop(owner, None)
        if record is None:
            return
        for grant in list(record.waiting):
            future = grant._future
            self._withdraw(grant)
            if future is not None and not future.done():
                names = list(grant.names)
                msg = f"{who(owner)} finished while still waiting for {names}"
                future.set_exception(LockUsageError(msg))
        for grant in list(record.grants):
            _log.warning("%s is done but still held %s; released", who(owner), list(grant.names))
            self.release(grant)
        owner.held = ()
        owner.awaiting = ()

    # -- arbitration ------------------------------------------------------

    def _count_below(self, owner: Owner, delta: int) -> None:
        below = self._below
        node: Owner | None = owner
        while node is not None:
            count = below.get(node, 0) + delta
            if count:
                below[node] = count
            else:
                del below[node]
            node = node.parent

    def _flush(self, leaves: Iterable[Leaf[OwnerT]]) -> None:
        """Serve every request that the change of ``leaves`` lets proceed."""
        self._work.extend(leaf for leaf in leaves if leaf.queue)
        if self._flushing:
            return
        self._flushing = True
        try:
            while self._work:
                self._scan(self._work.pop())
        finally:
            self._flushing = False
            self._work.clear()
            self._marked.clear()

    def _scan(self, leaf: Leaf[OwnerT]) -> None:
        queue = leaf.queue
        head = queue.first()
        while head is not None:
            if _rules.grantable(head, self._below):
                self._grant(head)
            elif head.preempt != SUSPEND or not self._lend(head):
                break
            head = queue.first()
        if head is None or not _rules.may_exempt(head, self._below):
            return
        for grant in list(queue):  # rare: descendants of a holder wait, look further
            if not grant.waiting:
                continue
            if _rules.grantable(grant, self._below):
                self._grant(grant)
            elif _rules.may_exempt(grant, self._below):
                if grant not in self._marked:
                    self._marked.add(grant)
                    self._work.extend(grant.leaves)
            else:
                return

    def _preempt(self, grant: Grant[OwnerT]) -> bool:
        """Cancel the holders in ``grant``'s way if all have a lower priority.

        A request that will not wait cancels nobody when a request queued ahead
        would be served before it: it is skipped, naming both.
        """
        blockers = _rules.blockers(grant)
        if not blockers or any(hold.priority >= grant.priority for hold, _ in blockers):
            return False
        if not grant.wait:
            ahead = _rules.queued_ahead(grant)
            if ahead is not None:
                leaf, other = ahead
                self._skip(grant, (leaf.resource, _rules.holder_in_way(grant, leaf), other))
        owner, done = grant.owner, set[Owner]()
        for hold, leaf in blockers:
            if hold.owner in done:
                continue
            done.add(hold.owner)
            name = leaf.resource.name
            reason = f"preempted by {who(owner)} (priority {grant.priority}) for {name!r}"
            if self._instruments:
                data = {"resource": name, "by": owner.id, "reason": reason}
                self._emit(EventKind.RESOURCE_PREEMPTED, hold, **data)
            hold.owner.cancel(reason)
        return True

    # -- lending (preempt="suspend") ---------------------------------------

    def _lend(self, grant: Grant[OwnerT]) -> bool:
        """Suspend the lower-priority holders in ``grant``'s way and grant it their leaves.

        Returns False (and changes nothing) if it may not (see `_loans.plan`).
        In recordings the lent holds end (``resource.released``, ``lent_to``)
        and start again when given back (``resource.acquired``, ``given_back``).
        """
        where = _loans.plan(grant)
        if where is None:
            return False
        owner, suspended = grant.owner, set[Owner]()
        for loan in self._loans.lend(grant, where):
            lender, name = loan.lender, loan.leaf.resource.name
            reason = f"suspended by {who(owner)} (priority {grant.priority}) for {name!r}"
            if self._instruments:
                data = {"resource": name, "by": owner.id, "reason": reason, "suspended": True}
                self._emit(EventKind.RESOURCE_PREEMPTED, loan.holds[0], **data)
                for hold in loan.holds:
                    self._emit(EventKind.RESOURCE_RELEASED, hold, leaves=[name], lent_to=owner.id)
            if lender not in suspended:
                suspended.add(lender)
                lender._suspend(reason, owner)
        self._grant(grant)
        return True

    def _unhold(self, leaf: Leaf[OwnerT], grant: Grant[OwnerT]) -> None:
        lender = self._loans.unhold(leaf, grant)
        if lender is not None:
            lender._unsuspend()

    def _give_back(self, leaves: tuple[Leaf[OwnerT], ...]) -> None:
        """Give back the loans on ``leaves`` whose borrowers let go; resume their lenders."""
        for leaf in leaves:
            if not leaf.lent:
                continue
            for loan, restored, lender in self._loans.give_back(leaf):
                if restored and self._instruments:
                    back = {"leaves": [leaf.resource.name], "given_back": True}
                    for hold in loan.holds:
                        self._emit(EventKind.RESOURCE_ACQUIRED, hold, **back)
                if lender is not None:
                    lender._unsuspend()

    def _skip(self, grant: Grant[OwnerT], why: _rules.Obstacle[OwnerT] | None = None) -> NoReturn:
        resource, holder, ahead = why if why is not None else _rules.obstacle(grant, self._below)
        queued = ahead.owner if ahead is not None else None
        if self._instruments:
            data = {
                "busy": resource.name,
                "holder": holder.id if holder is not None else None,
                "queued": queued.id if queued is not None else None,
            }
            self._emit(EventKind.RESOURCE_SKIPPED, grant, **data)
        priority = ahead.priority if ahead is not None else None
        raise ActionSkipped(resource, holder, queued=queued, queued_priority=priority)

    # -- bookkeeping ------------------------------------------------------

    @staticmethod
    def _sync(owner: OwnerT, record: _Record[OwnerT]) -> None:
        owner.held = _names(record.grants)
        owner.awaiting = _names(record.waiting)

    def _emit(self, kind: EventKind, grant: Grant[OwnerT], **data: object) -> None:
        owner = grant.owner
        data.setdefault("resources", list(grant.names))
        data.setdefault("leaves", [leaf.resource.name for leaf in grant.leaves])
        data.setdefault("priority", grant.priority)
        self._instruments.emit(ExecEvent(kind, self._clock(), owner.id, owner.name, data))
