"""The pytest plugin (``pytest11`` entry point ``pyrobots_aio``).

Fixtures:
    no_leaked_tasks: fails the test if an asyncio task it started is still
        pending when it ends (use it, or make it autouse in your conftest).
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest
import pytest_asyncio

if TYPE_CHECKING:
    from collections.abc import AsyncIterator


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_leaks: this test may leave asyncio tasks behind (not checked)."
    )


@pytest_asyncio.fixture
async def no_leaked_tasks(request: pytest.FixtureRequest) -> AsyncIterator[None]:
    """Fail the test if an asyncio task it started is still pending when it ends."""
    before = asyncio.all_tasks()
    yield
    if request.node.get_closest_marker("allow_leaks"):
        return
    await asyncio.sleep(0)  # let tasks that were just woken finish their last step
    current = asyncio.current_task()
    left = [t for t in asyncio.all_tasks() - before if t is not current and not t.done()]
    assert not left, f"tasks outlived the test: {left!r}"
