"""The pytest plugin (``pytest11`` entry point ``pyrobots_aio``).

Markers:
    virtual_time: run the async test on the virtual-time loop, where
        ``asyncio.sleep(3600)`` returns at once with ``loop.time()`` 3600 s later.

Fixtures:
    no_leaked_tasks: fails the test if an asyncio task it started is still
        pending when it ends (use it, or make it autouse in your conftest).
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

import pytest
import pytest_asyncio

from pyrobots_aio._core._clock import new_virtual_loop

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Mapping


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_leaks: this test may leave asyncio tasks behind (not checked)."
    )
    config.addinivalue_line(
        "markers", "virtual_time: run this async test on the virtual-time event loop."
    )


def pytest_asyncio_loop_factories(
    config: pytest.Config, item: pytest.Item
) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]]:
    """Run tests marked ``virtual_time`` on the virtual-time loop, the others as usual."""
    if item.get_closest_marker("virtual_time"):
        return {"virtual_time": new_virtual_loop}
    return {"asyncio": asyncio.new_event_loop}


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
