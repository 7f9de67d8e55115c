"""Per-tick controllers: what a base runs after each fresh sensor update.

A motion action hands a ``step()`` function to ``await base.control(step)``;
the base calls `Controllers.run` once its sensors are fresh (a simulator's
control tick, a ROS 2 odometry message), which calls every waiting ``step``:
it reads the state, sets the wheel command, and returns True when done. No
polling: the waiting action sleeps on a future that ``run`` resolves.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

from ..actions import current_action

if TYPE_CHECKING:
    from collections.abc import Callable

    from ..actions import ActionHandle


class Controllers:
    """The ``step`` functions waiting for a base's next sensor updates.

    Examples:
        >>> import asyncio
        >>> async def main() -> int:
        ...     controllers, calls = Controllers(), []
        ...     def step() -> bool:
        ...         calls.append(1)
        ...         return len(calls) == 3
        ...     waiting = asyncio.ensure_future(controllers.control(step))
        ...     await asyncio.sleep(0)
        ...     for _ in range(5):  # five sensor updates; the third ends the wait
        ...         controllers.run()
        ...     await waiting
        ...     return len(calls)
        >>> asyncio.run(main())
        3
    """

    __slots__ = ("_waiting",)

    def __init__(self) -> None:
        self._waiting: dict[
            Callable[[], bool], tuple[asyncio.Future[None], ActionHandle[Any] | None]
        ] = {}

    def __len__(self) -> int:
        return len(self._waiting)

    async def control(self, step: Callable[[], bool]) -> None:
        """Wait while `run` calls ``step()`` after each update, until it returns True.

        An exception raised by ``step`` ends the wait with that exception;
        cancelling the wait removes ``step``. While the calling action is
        paused, ``step`` is not called (its pause hook stopped the wheels).
        """
        fut = asyncio.get_running_loop().create_future()
        self._waiting[step] = (fut, current_action.get())
        try:
            await fut
        finally:
            self._waiting.pop(step, None)

    def run(self) -> None:
        """Call every waiting ``step`` once (the base's sensors are fresh)."""
        for step, (fut, handle) in list(self._waiting.items()):
            if fut.done() or (handle is not None and handle.paused):
                continue
            try:
                finished = step()
            except Exception as exc:  # the waiting action gets the error
                fut.set_exception(exc)
                continue
            if finished:
                fut.set_result(None)

    def fail(self, error: Exception) -> None:
        """End every wait with ``error`` (a base that lost its sensors: stale odometry)."""
        for fut, _ in self._waiting.values():
            if not fut.done():
                fut.set_exception(error)
        self._waiting.clear()

    def cancel(self) -> None:
        """Cancel every wait (the base is stopping)."""
        for fut, _ in self._waiting.values():
            if not fut.done():
                fut.cancel()
        self._waiting.clear()

    def __repr__(self) -> str:
        return f"<Controllers waiting={len(self._waiting)}>"
