"""Kernel timers as file descriptors (Linux ``timerfd``), for the loop watchdog.

A thread that blocks reading a timer's descriptor waits in the kernel, not
holding the GIL, and wakes only when the timer expires; another thread may
re-arm the timer meanwhile (pushing its expiry back) without waking it. That
is what lets the loop watchdog (`pyrobots_aio._core._blockwatch`) cost
nothing while the loop turns: waking a Python thread takes the GIL, and a
busy loop hands the GIL on only at its next ``select``, so every wake-up of a
polling thread would cost it (and the loop) dearly.

Python 3.13 has ``os.timerfd_create``; on 3.11 and 3.12 the C library's
functions are called through `ctypes` (they release the GIL, as every
``ctypes`` call does). `Timer` raises `OSError` where there is no such
thing (not Linux): the watchdog then polls.
"""

from __future__ import annotations

import ctypes
import os
import sys
import time

_TFD_NONBLOCK = os.O_NONBLOCK  # Linux defines TFD_NONBLOCK and TFD_CLOEXEC as these
_TFD_CLOEXEC = os.O_CLOEXEC


class _TimeSpec(ctypes.Structure):
    _fields_ = (("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long))


class _TimerSpec(ctypes.Structure):
    _fields_ = (("it_interval", _TimeSpec), ("it_value", _TimeSpec))


def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        create, settime = libc.timerfd_create, libc.timerfd_settime
    except (OSError, AttributeError):
        return None
    create.argtypes = (ctypes.c_int, ctypes.c_int)
    create.restype = ctypes.c_int
    settime.argtypes = (
        ctypes.c_int,
        ctypes.c_int,
        ctypes.POINTER(_TimerSpec),
        ctypes.c_void_p,
    )
    settime.restype = ctypes.c_int
    return libc


_LIBC = _libc()


def _spec(seconds: float) -> _TimeSpec:
    whole = int(seconds)
    return _TimeSpec(whole, int((seconds - whole) * 1e9))


class Timer:
    """One kernel timer on the monotonic clock, read through its descriptor `fd`.

    Args:
        blocking: Whether reading `fd` waits for the expiry (a thread's wait)
            or fails at once when it has not expired (for an event loop's
            reader).

    Raises:
        OSError: No kernel timers here (not Linux), or none left.

    Examples:
        >>> timer = Timer()
        >>> timer.arm(0.01)
        >>> timer.wait()  # blocks 10 ms, without the GIL
        1
        >>> timer.close()
    """

    __slots__ = ("_spec", "expires", "fd")

    def __init__(self, *, blocking: bool = True) -> None:
        if _LIBC is None:
            msg = "no timerfd here: kernel timers as file descriptors are Linux's"
            raise OSError(msg)
        flags = _TFD_CLOEXEC | (0 if blocking else _TFD_NONBLOCK)
        fd: int = _LIBC.timerfd_create(time.CLOCK_MONOTONIC, flags)
        if fd < 0:
            errno = ctypes.get_errno()
            raise OSError(errno, os.strerror(errno))
        self.fd = fd
        self._spec = _TimerSpec()
        self.expires = float("inf")
        """When it was last armed to expire (``time.monotonic``; inf: disarmed)."""

    def arm(self, seconds: float, period: float = 0.0) -> None:
        """Expire ``seconds`` from now (then every ``period`` seconds, if not 0).

        Re-arming forgets an expiry not read yet. ``seconds`` must be more than 0.
        """
        self._set(max(seconds, 1e-9), period)  # 0 would disarm it
        self.expires = time.monotonic() + seconds

    def disarm(self) -> None:
        """Stop it: it expires no more until armed again."""
        self._set(0.0, 0.0)
        self.expires = float("inf")

    def _set(self, value: float, interval: float) -> None:
        spec = self._spec
        spec.it_value = _spec(value)
        spec.it_interval = _spec(interval)
        if _LIBC is None or _LIBC.timerfd_settime(self.fd, 0, ctypes.byref(spec), None) < 0:
            errno = ctypes.get_errno()
            raise OSError(errno, os.strerror(errno))

    def wait(self) -> int:
        """How many times it expired since the last read (waits for one if blocking).

        0: a non-blocking timer that has not expired.
        """
        try:
            return int.from_bytes(os.read(self.fd, 8), sys.byteorder)
        except BlockingIOError:
            return 0

    def close(self) -> None:
        """Close its descriptor (idempotent)."""
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1
