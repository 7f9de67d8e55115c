"""ResourceManager: the lock state of one robot (``robot.resources``).

The manager keeps, for each plain resource it has seen, a `Leaf` (holds and
waiting line) and applies the rules of `_rules`. A hand-off is served by
scanning the lines of the leaves whose state changed, from the front, and
granting every request that can now proceed; a scan stops at the first
request that cannot and is not held up, since everything behind it on that
leaf yields to it.
Only when some descendant of a blocking holder waits (an exemption might
apply) does a scan go past it. Granted waiters are woken through their own
future: no thundering herd, no polling, and a hand-off costs the same with
one waiter or a thousand. Lending to ``preempt="suspend"`` requests is in
`_loans` (its docstring gives the semantics). A scan also looks past a
held-up request (`_rules.held_up`), at most `_rules.LOOKAHEAD` of them, so a
hand-off stays bounded with a thousand waiters.

The module is longer than most: the lock state and the bookkeeping that
keeps it consistent (records, counts, events) change together, in one place.
"""

from __future__ import annotations

import asyncio
import functools
import itertools
import logging
import math
from typing import TYPE_CHECKING, Generic, NoReturn

from .._core._events import (
    ResourceAcquired,
    ResourcePreempted,
    ResourceReleased,
    ResourceSkipped,
    ResourceWaiting,
)
from .._core._instrument import Instruments
from .._exceptions import ActionSkipped, LockUsageError, ResourceDeadlockError
from . import _cycles, _loans, _rules
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
    descends,
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


_NOTHING: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())


def _names(grants: list[Grant[OwnerT]]) -> tuple[str, ...]:
    """The names of the resources of ``grants``, each once, in order."""
    if len(grants) == 1:
        return grants[0].names
    return tuple(dict.fromkeys(name for grant in grants for name in grant.names))


def _loop_time() -> float:
    return asyncio.get_running_loop().time()


def _check_aging(value: object) -> float | None:
    """``value`` if it is None or a positive finite number of seconds; else `LockUsageError`."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < math.inf:
        msg = (
            f"aging must be a positive number of seconds (waiting worth one priority "
            f"level) or None, got {value!r}; e.g. aging=5.0"
        )
        raise LockUsageError(msg)
    return float(value)


class ResourceManager(Generic[OwnerT]):
    """The lock state of one robot (``robot.resources``): who holds what, who waits.

    Args:
        instruments: Where resource events go (waiting, acquired, released,
            preempted, skipped).
        clock: The time stamp of those events (and of waits, for aging); the
            running loop's clock by default.
        aging: Seconds of waiting worth one priority level (see `aging`);
            None (the default): strict priority.

    Policy: waiters are served by priority (with ``aging``, the priority
    raised by the time waited), then first come first served. A request never
    overtakes an earlier queued request of equal or higher priority that
    wants one of its resources (DESIGN §4), with one bounded exception
    against head-of-line blocking: a queued request that a holder holds up
    (it cannot run now anyway) lets later requests that can run now use its
    other, idle resources, at most ``_rules.BYPASS_LIMIT`` (16) times; then
    it keeps its place, so it is never starved. Holders of a lower priority
    are cancelled (``preempt=True``) or suspended (``preempt="suspend"``)
    only on request.

    Examples:
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
        self,
        instruments: Instruments | None = None,
        *,
        clock: Callable[[], float] | None = None,
        aging: float | None = None,
    ) -> None:
        self._aging = _check_aging(aging)
        self._instruments = instruments if instruments is not None else Instruments()
        self._clock = clock if clock is not None else _loop_time
        self._leaves: dict[str, Leaf[OwnerT]] = {}
        self._owners: dict[OwnerT, _Record[OwnerT]] = {}
        self._below: dict[Owner, int] = {}
        """For every owner, how many queued requests it or its descendants have."""
        self._seq = 0
        self._work: dict[Leaf[OwnerT], None] = {}
        """Leaves to scan, each once until scanned (an ordered set: newest scanned first)."""
        self._marked: set[Grant[OwnerT]] = set()
        self._flushing = False
        self._loans: _loans.Loans[OwnerT] = _loans.Loans()
        self._epoch: float | None = None

    @property
    def aging(self) -> float | None:
        """Seconds of waiting worth one priority level, or None for strict priority.

        With aging, a waiting request ranks as its priority plus the seconds it
        has waited divided by ``aging``: a request of priority 0 that has
        waited ``10 * aging`` seconds goes before a fresh request of priority
        10 (strict priority starves it for as long as higher ones keep
        coming). An earlier request of equal or higher priority always ranks
        at least as high, so it is never overtaken; a higher priority still
        wins against a short wait. Off by default: a reflex must outrank a
        motion however long the motion has waited, unless the program says
        how long a wait is worth. Set it while nothing waits.

        Examples:
            >>> import asyncio
            >>> from pyrobots_aio import Robot
            >>> async def main() -> float | None:
            ...     async with Robot() as robot:
            ...         robot.resources.aging = 2.0  # 2 s of waiting = 1 priority level
            ...         return robot.resources.aging
            >>> asyncio.run(main())
            2.0

        Raises:
            LockUsageError: Not a positive finite number (nor None), or set
                while requests wait (their places would change).
        """
        return self._aging

    @aging.setter
    def aging(self, value: float | None) -> None:
        checked = _check_aging(value)
        if self._below:
            msg = (
                f"cannot change aging to {value!r} while {sum(self._below.values())} "
                "requests wait; set it before they queue (e.g. at the start)"
            )
            raise LockUsageError(msg)
        self._aging = checked

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
            ResourceDeadlockError: Waiting would close a lock cycle (see
                `_cycles`): a holder in the way waits, directly or not, for
                what ``owner`` holds. The request is not queued.
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
        if not preempting:
            self._refuse_cycle(grant)
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
        if self._instruments:
            self._instruments.emit(ResourceReleased(*self._held(grant)))
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
                found.update(dict.fromkeys(state.lenders()))
        return list(found)

    def held(self) -> dict[Resource, OwnerT]:
        """Every plain resource held now, and its (innermost) holder."""
        return {s.resource: s.holds[-1].owner for s in self._leaves.values() if s.holds}

    def held_by(self, owner: OwnerT) -> tuple[str, ...]:
        """The names of the resources ``owner`` holds, each once, in the order taken.

        A resource lent to a ``preempt="suspend"`` request still counts as held
        by its lender, until the lender ends.
        """
        record = self._owners.get(owner)
        return () if record is None else _names(record.grants)

    def awaited_by(self, owner: OwnerT) -> tuple[str, ...]:
        """The names of the resources ``owner`` waits for, each once, in the order asked."""
        record = self._owners.get(owner)
        return () if record is None or not record.waiting else _names(record.waiting)

    def holdings(self, owner: OwnerT) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """`held_by` and `awaited_by` of ``owner`` at once (``robot.running()`` asks for both)."""
        record = self._owners.get(owner)
        if record is None:
            return _NOTHING
        return _names(record.grants), _names(record.waiting) if record.waiting else ()

    def __repr__(self) -> str:
        parts = [self._describe(s) for s in self._leaves.values() if s.holds or s.queue]
        return f"<ResourceManager {'; '.join(parts) if parts else 'idle'}>"

    @staticmethod
    def _describe(state: Leaf[OwnerT]) -> str:
        what = f"held by {holder(state.holds[-1].owner)}" if state.holds else "free"
        lenders = [who(lender) for lender in state.lenders()]
        if lenders:
            what += f" (lent by {', '.join(lenders)})"
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
        aging, rank = self._aging, None
        if aging is not None:  # from the first aged request on: small, exact-enough numbers
            now = self._clock()
            if self._epoch is None:
                self._epoch = now
            rank = options[1] - (now - self._epoch) / aging
        return Grant(self, owner, resources, tuple(leaves), options, seq=self._seq, rank=rank)

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
        compound = len(grant.leaves) > 1
        for leaf in grant.leaves:
            leaf.queue.add(grant)
            leaf.compounds += compound
        self._count_below(owner, 1)
        if self._instruments:
            self._instruments.emit(ResourceWaiting(*self._held(grant)))
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
        compound = len(grant.leaves) > 1
        for leaf in grant.leaves:
            leaf.queue.discard(grant)
            leaf.compounds -= compound
        self._count_below(grant.owner, -1)
        record = self._owners.get(grant.owner)
        if record is not None:
            record.waiting.remove(grant)
        if self._instruments:
            self._instruments.emit(ResourceReleased(*self._held(grant), withdrawn=True))
        self._flush(grant.leaves)

    def _grant(self, grant: Grant[OwnerT]) -> None:
        waited = grant._state == WAITING
        grant._state = HELD
        owner = grant.owner
        record = self._record(owner)
        compound = waited and len(grant.leaves) > 1
        if waited:
            for leaf in grant.leaves:
                leaf.queue.discard(grant)
                leaf.compounds -= compound
        queued = any(leaf.queue for leaf in grant.leaves)
        if queued:
            for other in _rules.bypassed(grant):
                other.bypassed += 1
        for leaf in grant.leaves:
            leaf.holds.append(grant)
        if queued:
            self._held_up_now(grant)
        if waited:
            record.waiting.remove(grant)
            self._count_below(owner, -1)
            if grant._future is not None and not grant._future.done():
                grant._future.set_result(None)
        record.grants.append(grant)
        if self._instruments:
            self._instruments.emit(ResourceAcquired(*self._held(grant)))
        self._flush(grant.leaves)

    def _held_up_now(self, grant: Grant[OwnerT]) -> None:
        """Look again behind the compound requests that ``grant`` has just held up.

        Before the grant, its leaves were free: a compound request queued on
        them may just have become held up, so the requests queued behind it
        on its other leaves may now go.
        """
        mine = grant.leaves  # flushed after the grant anyway
        for leaf in mine:
            if not leaf.compounds:
                continue
            for other in itertools.islice(leaf.queue, _rules.LOOKAHEAD + 1):
                if len(other.leaves) > 1 and other not in self._marked and _rules.held_up(other):
                    self._marked.add(other)
                    self._work.update(
                        (x, None) for x in other.leaves if not x.holds and x not in mine
                    )

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
        self._work.update((leaf, None) for leaf in leaves if leaf.queue)
        if self._flushing:
            return
        self._flushing = True
        try:
            while self._work:
                self._scan(self._work.popitem()[0])
        finally:
            self._flushing = False
            self._work.clear()
            self._marked.clear()

    def _scan(self, leaf: Leaf[OwnerT]) -> None:
        queue = leaf.queue
        head = queue.first()
        while head is not None and self._serve(head):
            head = queue.first()
        if head is None:
            return
        skip = not leaf.holds and _rules.held_up(head)
        exempting = _rules.may_exempt(head, self._below)
        if not skip and not exempting:
            return
        passes = _rules.LOOKAHEAD + 1 if skip else 0
        # Look past a request that others need not wait for: at most LOOKAHEAD
        # held-up ones, unless descendants of a holder wait (rare: all of them).
        line = list(queue) if exempting else list(itertools.islice(queue, passes + 1))
        for grant in line:
            if not grant.waiting:
                continue
            if self._serve(grant):
                passes = passes if not leaf.holds else 0
                continue
            if _rules.may_exempt(grant, self._below):
                if grant not in self._marked:
                    self._marked.add(grant)
                    self._work.update(dict.fromkeys(grant.leaves))
            elif passes and _rules.held_up(grant):
                passes -= 1
            else:
                return

    def _serve(self, grant: Grant[OwnerT]) -> bool:
        """Grant ``grant`` if it may be served now (lending to it if it suspends)."""
        if _rules.grantable(grant, self._below):
            self._grant(grant)
            return True
        return grant.preempt == SUSPEND and self._lend(grant)

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
                event = ResourcePreempted(*self._held(hold), name, owner.id, reason)
                self._instruments.emit(event)
            hold.owner.cancel(reason)
        return True

    # -- lock cycles --------------------------------------------------------

    def _refuse_cycle(self, grant: Grant[OwnerT]) -> None:
        """Raise `ResourceDeadlockError` if ``grant`` waiting would close a lock cycle."""
        if not any(_rules.holder_in_way(grant, leaf) is not None for leaf in grant.leaves):
            return
        cycle = _cycles.find_cycle(grant, self._waits_of)
        if cycle is None:
            return
        if self._instruments:
            steps = tuple((w.id, name, h.id) for w, name, h in cycle)
            _, busy, holder_in_way = cycle[0]
            event = ResourceSkipped(*self._held(grant), busy, holder_in_way.id, deadlock=steps)
            self._instruments.emit(event)
        raise ResourceDeadlockError(cycle)

    def _waits_of(self, hold: Grant[OwnerT]) -> list[Grant[OwnerT]]:
        """The waiting requests to serve before ``hold`` can be released."""
        holder = hold.owner
        if not self._below.get(holder):
            return []
        record = self._owners.get(holder)
        found = list(record.waiting) if record is not None else []
        if hold.until_done:  # released once the holder is done: its descendants' waits count
            for owner, other in self._owners.items():
                if other.waiting and owner is not holder and descends(owner, holder):
                    found.extend(other.waiting)
        return found

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
                held = self._held(loan.holds[0])
                self._instruments.emit(
                    ResourcePreempted(*held, name, owner.id, reason, suspended=True)
                )
                for hold in loan.holds:
                    lent = ResourceReleased(*self._held(hold, name), lent_to=owner.id)
                    self._instruments.emit(lent)
            if lender not in suspended:
                suspended.add(lender)
                lender.suspend(reason, owner)
        self._grant(grant)
        return True

    def _unhold(self, leaf: Leaf[OwnerT], grant: Grant[OwnerT]) -> None:
        lender = self._loans.unhold(leaf, grant)
        if lender is not None:
            lender.unsuspend()

    def _give_back(self, leaves: tuple[Leaf[OwnerT], ...]) -> None:
        """Give back the loans on ``leaves`` whose borrowers let go; resume their lenders."""
        for leaf in leaves:
            if not leaf.lent:
                continue
            for loan, restored, lender in self._loans.give_back(leaf):
                if restored and self._instruments:
                    for hold in loan.holds:
                        held = self._held(hold, leaf.resource.name)
                        self._instruments.emit(ResourceAcquired(*held, given_back=True))
                if lender is not None:
                    lender.unsuspend()

    def _skip(self, grant: Grant[OwnerT], why: _rules.Obstacle[OwnerT] | None = None) -> NoReturn:
        resource, holder, ahead = why if why is not None else _rules.obstacle(grant, self._below)
        queued = ahead.owner if ahead is not None else None
        if self._instruments:
            holder_id = holder.id if holder is not None else None
            queued_id = queued.id if queued is not None else None
            event = ResourceSkipped(*self._held(grant), resource.name, holder_id, queued_id)
            self._instruments.emit(event)
        priority = ahead.priority if ahead is not None else None
        raise ActionSkipped(resource, holder, queued=queued, queued_priority=priority)

    # -- bookkeeping ------------------------------------------------------

    def _held(
        self, grant: Grant[OwnerT], lent: str | None = None
    ) -> tuple[float, int, str, tuple[str, ...], tuple[str, ...], int]:
        """What every resource event about ``grant`` starts with (only ``lent``, lent or back)."""
        owner = grant.owner
        leaves = (lent,) if lent is not None else tuple(leaf.resource.name for leaf in grant.leaves)
        return self._clock(), owner.id, owner.name, grant.names, leaves, grant.priority
