"""The grace ladder: cleanup after a cancellation is bounded in time, in two steps.

What was cancelled gets a grace period (``cancel_grace``) to clean up. If it
still runs after one grace, it is cancelled again with a warning (`Stage.ESCALATE`);
if it still runs after a second grace, it is given up with an error
(`Stage.ABANDON`), so that a shutdown always completes. The executive bounds
actions with a ladder, the event manager the tasks of monitor callbacks; what
each stage does (and says) is theirs, the timing is here.

All deadlines are one grace apart, so the queue of a ladder is in deadline
order and one timer serves it: watching a thousand cancelled actions costs one
timer, not a thousand.
"""

from __future__ import annotations

import enum
from collections import deque
from typing import TYPE_CHECKING, Generic, TypeVar

from ._loops import clock_of

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

T = TypeVar("T")


class Stage(enum.Enum):
    """A step of the ladder, reached when what was cancelled still runs."""

    ESCALATE = "escalate"
    """One grace after the cancellation: cancel it again, with a warning."""
    ABANDON = "abandon"
    """A grace after escalating: give it up, with an error."""


class Ladder(Generic[T]):
    """Calls ``step(item, stage)`` a grace after `watch`, then a grace after escalating.

    ``step`` returns whether ``item`` is still to be watched: `Stage.ABANDON`
    follows `Stage.ESCALATE` only if the escalation returned True. An item
    done meanwhile is for ``step`` to notice (it returns False).

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio.sim import run
        >>> async def main() -> list[tuple[str, str, float]]:
        ...     loop = asyncio.get_running_loop()
        ...     seen = []
        ...     def step(item: str, stage: Stage) -> bool:
        ...         seen.append((item, stage.value, loop.time()))
        ...         return True
        ...     ladder = Ladder(loop, 2.0, step)
        ...     ladder.watch("cleanup")
        ...     await asyncio.sleep(5)
        ...     ladder.close()
        ...     return seen
        >>> run(main)  # virtual time
        [('cleanup', 'escalate', 2.0), ('cleanup', 'abandon', 4.0)]
    """

    __slots__ = ("_clock", "_loop", "_queue", "_step", "_timer", "grace")

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        grace: float,
        step: Callable[[T, Stage], bool],
    ) -> None:
        self._loop = loop
        self._clock = clock_of(loop)
        self.grace = grace
        self._step = step
        self._queue: deque[tuple[float, Stage, T]] = deque()
        self._timer: asyncio.TimerHandle | None = None

    def watch(self, item: T) -> None:
        """Start the ladder for ``item``: its first step is one grace from now."""
        self._queue.append((self._clock() + self.grace, Stage.ESCALATE, item))
        if self._timer is None:
            self._arm()

    def close(self) -> None:
        """Stop watching everything (nothing is called any more)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._queue.clear()

    def _arm(self) -> None:
        """Set the timer at the earliest deadline, if anything is watched."""
        if self._queue:
            self._timer = self._loop.call_at(self._queue[0][0], self._due)

    def _due(self) -> None:
        self._timer = None
        now = self._clock()
        queue = self._queue
        while queue and queue[0][0] <= now:
            _, stage, item = queue.popleft()
            if self._step(item, stage) and stage is Stage.ESCALATE:
                queue.append((self._clock() + self.grace, Stage.ABANDON, item))
        if self._timer is None:  # unless a step watched something (and armed it)
            self._arm()
