"""Where a suspended coroutine is: the ``file:line`` of its innermost user frame."""

from __future__ import annotations

import asyncio
import inspect
import os
from collections.abc import Callable
from typing import Any

import anyio

_PACKAGE = os.path.dirname(os.path.dirname(__file__))
# The executive's own layers; the simulator's actions (sim/) are reported like user code.
_INTERNAL = (
    *(os.path.dirname(module.__file__ or "") + os.sep for module in (asyncio, anyio)),
    *(
        os.path.join(_PACKAGE, part) + os.sep
        for part in ("_core", "actions", "events", "resources", "robot", "state")
    ),
)


def location(coro: Any) -> str | None:
    """Follow the await chain of ``coro`` down; return the innermost frame outside asyncio.

    Frames of asyncio, anyio and the executive itself are skipped, so a body
    suspended in ``await robot.sleep(1)`` reports the line of that await; when
    every frame is internal (waiting for a lock), None.
    """
    where = None
    node = coro
    while node is not None:
        frame = getattr(node, "cr_frame", None) or getattr(node, "gi_frame", None)
        frame = frame or getattr(node, "ag_frame", None)
        if frame is not None and not frame.f_code.co_filename.startswith(_INTERNAL):
            where = f"{frame.f_code.co_filename}:{frame.f_lineno}"
        node = (
            getattr(node, "cr_await", None)
            or getattr(node, "gi_yieldfrom", None)
            or getattr(node, "ag_await", None)
        )
    return where


def definition(fn: Callable[..., object]) -> str | None:
    """The ``file:line`` where ``fn`` (unwrapped from its decorators) is defined."""
    code = getattr(inspect.unwrap(fn), "__code__", None)
    return None if code is None else f"{code.co_filename}:{code.co_firstlineno}"
