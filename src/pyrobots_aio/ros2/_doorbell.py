"""Doorbells: DDS wakes the event loop itself, through an eventfd, with no thread between.

rcl lets a subscription (or one of its events) call ``callback(user_data,
count)`` from DDS's own thread as soon as something new arrives; rclcpp's
events executor is built on it. The bridge hands it libc's
``eventfd_write(fd, value)``, with an eventfd's number as ``user_data``: on
the 64-bit ABIs allowed here (x86-64 and AArch64) both functions take their
first two integer arguments in the same two registers, so ``fd`` receives
the eventfd and ``value`` the count. No Python runs on DDS's thread (which
would have to take the GIL) and no thread of the bridge's wakes up: the
loop's selector sees the eventfd readable, and the loop takes the messages
itself.

Measured beside a plain rclpy subscription callback in another process, the
hop through the receiver thread (its wake-up, then the loop's, and the GIL
handed between the two) made the bridge 1.2x slower from topic to monitor
at the median, 3-4x at the 99th percentile on a loaded machine; rung
directly, it is as fast as plain rclpy.

Where a piece is missing (another system or architecture, an rcl without
these functions, an RMW that does not support them, a loop without
``add_reader``), `DoorbellUnavailable` says so and the receiver thread takes
the messages instead.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import platform
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ._rclpy import rclpy_module

if TYPE_CHECKING:
    import asyncio
    from collections.abc import Callable

_MACHINES = ("x86_64", "amd64", "aarch64", "arm64")
"""Where ``eventfd_write(int, uint64_t)`` reads ``callback(const void *, size_t)``'s arguments."""


class DoorbellUnavailable(Exception):
    """An rcl entity cannot ring the loop here; the message names what is missing."""


@dataclass(frozen=True, slots=True)
class _Rcl:
    """rcl's setters of listener callbacks, and what they are given."""

    on_message: Any  # rcl_subscription_set_on_new_message_callback
    on_event: Any  # rcl_event_set_callback
    reset_error: Any  # rcutils_reset_error: a refusal leaves rcl's error state set
    ring: int  # the address of libc's eventfd_write


@functools.cache
def _rcl() -> _Rcl | str:
    """The setters of rcl and libc's ``eventfd_write``, or why they cannot be used here."""
    if sys.platform != "linux" or platform.machine().lower() not in _MACHINES:
        return f"no eventfd doorbell on {sys.platform} {platform.machine()}"
    try:  # rclpy's extension has loaded both libraries already: these find them
        rcl = ctypes.CDLL("librcl.so")
        rcutils = ctypes.CDLL("librcutils.so")
        setters = rcl.rcl_subscription_set_on_new_message_callback, rcl.rcl_event_set_callback
        reset_error = rcutils.rcutils_reset_error
        ring = ctypes.cast(ctypes.CDLL(None).eventfd_write, ctypes.c_void_p).value
    except (OSError, AttributeError) as err:
        return f"rcl's listener callbacks cannot be reached ({err})"
    for setter in setters:
        setter.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        setter.restype = ctypes.c_int
    assert ring is not None  # a function's address
    return _Rcl(*setters, reset_error, ring)


def doorbells_available() -> bool:
    """Whether rcl entities can ring the loop on this system (the RMW may still refuse)."""
    return isinstance(_rcl(), _Rcl)


class Doorbell:
    """An eventfd an rcl entity rings from DDS's thread: ``answer()`` runs on the loop then.

    Args:
        loop: The event loop that answers (its selector watches the eventfd).
        handle: The rclpy handle of a subscription (rung for each new message)
            or of an event (``event=True``).
        answer: Called on the loop when the bell has rung; `rings` tells how often.

    Raises:
        DoorbellUnavailable: This system, rcl, the RMW or the loop cannot do it.
    """

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        handle: Any,
        answer: Callable[[], None],
        *,
        event: bool = False,
    ) -> None:
        rcl = _rcl()
        if not isinstance(rcl, _Rcl):
            raise DoorbellUnavailable(rcl)
        self._rcl, self._loop, self._handle = rcl, loop, handle
        self._set = rcl.on_event if event else rcl.on_message
        self._fd = os.eventfd(0, os.EFD_CLOEXEC | os.EFD_NONBLOCK)
        self._hung = False
        try:
            loop.add_reader(self._fd, answer)
        except NotImplementedError as err:  # a loop without a selector (Windows' proactor)
            os.close(self._fd)
            msg = f"{type(loop).__name__} cannot watch a file descriptor"
            raise DoorbellUnavailable(msg) from err
        try:
            self._hang()
        except BaseException:
            self.close()
            raise

    def _hang(self) -> None:
        with self._handle:  # not destroyed meanwhile
            refused = self._set(self._handle.pointer, self._rcl.ring, self._fd)
        if refused:
            self._rcl.reset_error()
            msg = f"the RMW refuses listener callbacks (rcl returned {refused})"
            raise DoorbellUnavailable(msg)
        self._hung = True  # DDS may ring from now on (at once, for what it holds already)

    def rings(self) -> int:
        """What the bell was rung with since the last look (a subscription's: new messages)."""
        try:
            return os.eventfd_read(self._fd)
        except BlockingIOError:  # not rung
            return 0

    def close(self) -> None:
        """Unhang the bell (DDS rings no more once this returns) and close the eventfd."""
        if self._hung:
            self._hung = False
            invalid = rclpy_module("rclpy.impl.implementation_singleton").rclpy_implementation
            # Unhooking waits for a ring in progress; a destroyed entity rings no more.
            with contextlib.suppress(invalid.InvalidHandle), self._handle:
                self._set(self._handle.pointer, None, None)
        if self._fd >= 0:
            self._loop.remove_reader(self._fd)
            os.close(self._fd)
            self._fd = -1
