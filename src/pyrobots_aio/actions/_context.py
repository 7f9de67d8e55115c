"""The current action, tracked per task through a context variable."""

from __future__ import annotations

from contextvars import ContextVar
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._handle import ActionHandle

current_action: ContextVar[ActionHandle[Any] | None] = ContextVar(
    "pyrobots_aio.current_action", default=None
)
"""The action whose body (or cleanup) the running task belongs to; None outside actions."""
