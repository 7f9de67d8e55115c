"""The two builds of the actions core: compiled (mypyc and C) in a wheel, Python everywhere else."""

from __future__ import annotations

import asyncio
import types
import weakref
from collections.abc import Generator
from typing import Any

import pytest
from build_support import BUILD, EXPECTED_BUILD, trampolines

from pyrobots_aio import Robot, action
from pyrobots_aio.actions import BoundAction, _handle, _pause
from pyrobots_aio.actions._pause import PyStepped, hold

TRAMPOLINES = pytest.mark.parametrize("trampoline", trampolines())


def test_the_installed_build_is_the_one_expected() -> None:
    assert BUILD == EXPECTED_BUILD
    if BUILD == "compiled":
        assert _handle.__file__ is not None
        assert not _handle.__file__.endswith(".py")
        assert _pause.Stepped is not PyStepped
    else:
        assert _pause.Stepped is PyStepped


@action
async def idle(robot: Robot) -> None:
    await robot.sleep(0)


@pytest.mark.asyncio
async def test_handles_refuse_weak_references_in_either_build() -> None:
    """A compiled class's weak references are unsafe: both builds refuse them alike."""
    async with Robot() as robot:
        handle = idle(robot)
        with pytest.raises(TypeError, match="weak reference"):
            weakref.ref(handle)
        with pytest.raises(TypeError, match="weak reference"):
            weakref.ref(BoundAction(idle, robot))
        await handle


@types.coroutine
def once() -> Generator[str, None, None]:
    yield "step"


def _body(value: object, step: Any = once) -> Any:
    async def body() -> object:
        await step()
        return value

    return body()


@pytest.mark.asyncio
@TRAMPOLINES
@pytest.mark.parametrize("value", [None, (1, 2), KeyError("a value, not an error"), "done"])
async def test_the_trampoline_returns_what_the_body_returns(
    trampoline: type[PyStepped[object]], value: object
) -> None:
    async with Robot() as robot:
        handle = idle(robot)
        stepped = trampoline(hold, handle._executive, handle, _body(value))
        assert next(stepped) == "step"
        with pytest.raises(StopIteration) as stop:
            next(stepped)
        assert stop.value.value is value
        stepped = trampoline(hold, handle._executive, handle, _body(value))
        assert stepped.send(None) == "step"
        with pytest.raises(StopIteration) as stop:
            stepped.send(None)
        assert stop.value.value is value
        body = _body(value, lambda: asyncio.sleep(0))
        awaited = trampoline(hold, handle._executive, handle, body)
        assert await awaited is value  # as the task awaits it
        await handle


@pytest.mark.asyncio
@TRAMPOLINES
async def test_the_trampoline_refuses_a_throw_of_what_is_no_exception(
    trampoline: type[PyStepped[object]],
) -> None:
    async with Robot() as robot:
        handle = idle(robot)
        body = _body(None)
        stepped = trampoline(hold, handle._executive, handle, body)
        assert next(stepped) == "step"
        with pytest.raises(TypeError):
            stepped.throw(42)
        with pytest.raises(ValueError, match="stop"):
            stepped.throw(ValueError, "stop")  # the body does not catch it: it ends
        await handle
        body.close()


def test_the_trampoline_takes_four_arguments() -> None:
    for trampoline in (p.values[0] for p in trampolines() if p.values[0] is not None):
        with pytest.raises(TypeError):
            trampoline(hold, None, None)
        with pytest.raises(TypeError):
            trampoline(hold, None, None, None, None)
