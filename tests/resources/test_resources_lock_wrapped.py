"""``@lock`` under a user decorator: held until the action is done if ``__wrapped__`` is kept."""

from __future__ import annotations

import asyncio
import functools
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

import pytest

from pyrobots_aio import Robot, action
from pyrobots_aio.actions import lock
from pyrobots_aio.resources import Resource

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

P = ParamSpec("P")
T = TypeVar("T")
WHEELS = Resource("wheels")


def passthrough(fn: Callable[P, Coroutine[Any, Any, T]]) -> Callable[P, Coroutine[Any, Any, T]]:
    """A user decorator that keeps ``__wrapped__`` (functools.wraps)."""

    @functools.wraps(fn)
    async def wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        return await fn(*args, **kwargs)

    return wrapper


def opaque(fn: Callable[P, Coroutine[Any, Any, T]]) -> Callable[P, Coroutine[Any, Any, T]]:
    """A user decorator that hides what it wraps (no functools.wraps)."""

    async def opaque_wrapper(*args: P.args, **kwargs: P.kwargs) -> T:
        return await fn(*args, **kwargs)

    return opaque_wrapper


@action
async def unlocked_child(robot: Robot, stopped: list[object]) -> None:
    try:
        await asyncio.sleep(3600)
    finally:
        await asyncio.sleep(0)  # its cleanup still drives the wheels its parent locked
        stopped.append(robot.resources.owner(WHEELS))


@action
@passthrough
@lock(WHEELS)
async def decorated_parent(robot: Robot, stopped: list[object]) -> None:
    unlocked_child(robot, stopped)
    await asyncio.sleep(0)


@action
@opaque
@lock(WHEELS)
async def hidden_parent(robot: Robot, stopped: list[object]) -> None:
    unlocked_child(robot, stopped)
    await asyncio.sleep(0)


@pytest.mark.asyncio
async def test_a_wrapping_decorator_between_action_and_lock_still_holds_until_done() -> None:
    stopped: list[object] = []
    async with Robot() as robot:
        parent = decorated_parent(robot, stopped)
        await parent
        assert stopped == [parent]
        assert robot.resources.owner(WHEELS) is None


@pytest.mark.asyncio
async def test_a_decorator_hiding_the_lock_makes_it_hold_for_the_call_only() -> None:
    """The documented limit: without ``__wrapped__`` the lock is held like a helper's."""
    stopped: list[object] = []
    async with Robot() as robot:
        await hidden_parent(robot, stopped)
        assert stopped == [None]
        assert robot.resources.owner(WHEELS) is None
