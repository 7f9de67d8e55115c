"""`SignalSafeLoop`: a selector loop that lets go of the signal wake-up before it closes.

asyncio's Unix loop (3.11, 3.12) closes its self-pipe first and only then
removes its signal handlers, which is when it resets the signal wake-up file
descriptor. A signal in between (a second Ctrl-C as the program exits) is
written to a closed file, and Python prints "Exception ignored ... Bad file
descriptor" with a traceback. Every loop pyrobots_aio makes closes the other
way round.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import threading


class SignalSafeLoop(asyncio.SelectorEventLoop):
    """An ``asyncio.SelectorEventLoop`` whose ``close`` resets the signal wake-up first.

    Examples:
        >>> import asyncio
        >>> loop = SignalSafeLoop()
        >>> loop.run_until_complete(asyncio.sleep(0, "done"))
        'done'
        >>> loop.close()
    """

    def close(self) -> None:
        """Reset the wake-up of this loop's signal handlers, then close as asyncio does."""
        # asyncio keeps its handlers in a private dict; only a loop that took signals
        # (in the main thread) owns the wake-up descriptor to reset.
        taken = getattr(self, "_signal_handlers", None)
        if taken and threading.current_thread() is threading.main_thread():
            with contextlib.suppress(ValueError, OSError):
                signal.set_wakeup_fd(-1)
        super().close()
