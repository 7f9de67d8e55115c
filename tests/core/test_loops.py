"""Which loop the caller is on, checked cheaply; the clock an action or a state write reads."""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any

import pytest

from pyrobots_aio import ActionHandle, EventLoopError, Outcome, Robot, action
from pyrobots_aio._core._loops import clock_of, current_loop, makes_plain_tasks, running_here
from pyrobots_aio.loops import VirtualTimeLoop
from pyrobots_aio.state import StateStore


@action
async def nap(robot: Robot, seconds: float = 0.01) -> str:
    await robot.sleep(seconds)
    return "rested"


def test_running_here_agrees_with_the_running_loop_in_every_case() -> None:
    here = threading.get_ident()
    idle = asyncio.new_event_loop()
    seen: dict[str, bool] = {}

    async def inside() -> None:
        loop = asyncio.get_running_loop()
        seen["its own loop, on its thread"] = running_here(loop, here)
        assert current_loop() is loop
        seen["another loop of this thread, not running"] = running_here(idle, here)
        elsewhere: list[bool] = []
        worker = threading.Thread(target=lambda: elsewhere.append(running_here(loop, here)))
        worker.start()
        await asyncio.to_thread(worker.join)
        seen["its own loop, from another thread"] = elsewhere[0]

    try:
        asyncio.run(inside())
        seen["no loop running at all"] = running_here(idle, here)
    finally:
        idle.close()
    assert seen == {
        "its own loop, on its thread": True,
        "another loop of this thread, not running": False,
        "its own loop, from another thread": False,
        "no loop running at all": False,
    }


def test_a_robot_used_from_another_loop_of_its_own_thread_says_so() -> None:
    """The robot's loop is stopped; a second loop runs in the same thread and uses the robot."""
    home = asyncio.new_event_loop()
    robot = Robot(block_threshold=None)
    home.run_until_complete(robot.__aenter__())
    handle = home.run_until_complete(_started(robot))
    refused: list[str] = []

    async def from_another_loop() -> None:
        for attempt in (
            lambda: nap(robot),
            lambda: robot.state.update(bumper=True),
            lambda: robot.state.set("bumper", True),
            lambda: handle.__await__().send(None),
        ):
            with pytest.raises(EventLoopError, match="from another event loop") as caught:
                attempt()
            refused.append(str(caught.value).split(" from ")[0])

    try:
        asyncio.run(from_another_loop())
        assert home.run_until_complete(handle.wait_done()) is Outcome.SUCCEEDED
        assert robot.state["bumper"] is False  # the refused writes wrote nothing
    finally:
        home.run_until_complete(robot.__aexit__(None, None, None))
        home.close()
    assert refused == [
        "cannot start action 'nap'",
        "cannot write state keys ['bumper']",
        "cannot write state key 'bumper'",
        f"cannot await action nap#{handle.id}",
    ]


async def _started(robot: Robot) -> ActionHandle[str]:
    robot.state.bumper = False
    return nap(robot, 0.5)


def test_the_clock_of_asyncio_s_loop_is_the_monotonic_clock_itself() -> None:
    loop = asyncio.new_event_loop()
    try:
        assert clock_of(loop) is time.monotonic
        loop.time = lambda: 42.0  # type: ignore[method-assign]
        assert clock_of(loop)() == 42.0  # a patched loop keeps its own clock
    finally:
        loop.close()
    virtual = VirtualTimeLoop()
    try:
        assert clock_of(virtual) == virtual.time
    finally:
        virtual.close()


def test_plain_tasks_only_where_create_task_is_asyncio_s_own_and_no_factory_is_set() -> None:
    loop = asyncio.new_event_loop()
    try:
        assert makes_plain_tasks(loop)
        loop.set_task_factory(lambda loop, coro: asyncio.Task(coro, loop=loop))
        assert not makes_plain_tasks(loop)
        loop.set_task_factory(None)
        loop.create_task = lambda coro, name=None: asyncio.Task(coro, loop=loop)  # type: ignore[assignment, method-assign]
        assert not makes_plain_tasks(loop)
    finally:
        loop.close()


@action
async def task_name(robot: Robot) -> tuple[str, str]:
    task = asyncio.current_task()
    assert task is not None
    return type(task).__name__, task.get_name()


def test_an_action_s_task_comes_from_the_loop_s_task_factory_when_it_has_one() -> None:
    made: list[asyncio.Task[Any]] = []

    def factory(loop: asyncio.AbstractEventLoop, coro: Any) -> asyncio.Task[Any]:
        made.append(asyncio.Task(coro, loop=loop))  # (the loop names it next)
        return made[-1]

    async def main(with_factory: bool) -> tuple[str, str]:
        if with_factory:
            asyncio.get_running_loop().set_task_factory(factory)
        async with Robot() as robot:
            return await task_name(robot)

    assert asyncio.run(main(with_factory=False)) == ("Task", "task_name#1")
    assert made == []
    assert asyncio.run(main(with_factory=True)) == ("Task", "task_name#1")
    assert "task_name#1" in [task.get_name() for task in made]


def test_a_bound_store_stamps_with_its_loop_s_clock_and_an_unbound_one_with_the_running_loop() -> (
    None
):
    store = StateStore()
    virtual = VirtualTimeLoop()

    async def write(key: str, after: float) -> float:
        await asyncio.sleep(after)
        store.set(key, 1)
        return store.timestamp(key)

    try:
        store.bind(virtual)
        assert virtual.run_until_complete(write("bound", 7.5)) == 7.5
        store.bind(None)
        assert virtual.run_until_complete(write("unbound", 2.0)) == 9.5
    finally:
        virtual.close()
    given = StateStore(clock=lambda: -1.0)
    given.bind(None)
    given.set("k", 0)
    assert given.timestamp("k") == -1.0  # a clock given to the store is never replaced
