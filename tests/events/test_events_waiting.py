"""Waiting: robot.wait, monitor.wait, and one-shot monitors (robot.on)."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import Robot, StateError

pytestmark = pytest.mark.virtual_time


async def _write_later(robot: Robot, delay: float, **values: object) -> None:
    await robot.sleep(delay)
    robot.state.update(values)


@pytest.mark.asyncio
async def test_wait_on_a_level_that_already_holds_returns_at_once() -> None:
    async with Robot() as robot:
        robot.state.battery = 0.1
        t0 = robot.time()
        assert await robot.wait("battery", below=0.2) == 0.1
        assert robot.time() == t0
        assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_wait_on_an_edge_waits_for_the_next_change_even_if_the_value_is_there() -> None:
    async with Robot() as robot:
        robot.state.docked = True
        t0 = robot.time()
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(_write_later(robot, 1.0, docked=False))
            tasks.create_task(_write_later(robot, 2.0, docked=True))
            assert await robot.wait("docked", becomes=True) is True
        assert robot.time() - t0 == 2.0


@pytest.mark.asyncio
async def test_wait_with_held_for_counts_the_hold_from_the_call() -> None:
    async with Robot() as robot:
        robot.state.docked = True
        t0 = robot.time()
        assert await robot.wait("docked", value=True, held_for=1.5) is True
        assert robot.time() - t0 == 1.5


@pytest.mark.asyncio
async def test_wait_on_increase_returns_the_value_that_met_it() -> None:
    async with Robot() as robot:
        robot.state.scale = 1.0
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(_write_later(robot, 0.5, scale=1.5))
            tasks.create_task(_write_later(robot, 1.0, scale=2.25))
            assert await robot.wait("scale", increase=1.0) == 2.25


@pytest.mark.asyncio
async def test_wait_on_a_predicate() -> None:
    async with Robot() as robot:
        robot.state.update(x=0.0, y=0.0)
        t0 = robot.time()
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(_write_later(robot, 1.0, x=3.0))
            tasks.create_task(_write_later(robot, 2.0, y=4.0))
            far = await robot.wait(lambda r: (r.state.x**2 + r.state.y**2) ** 0.5 >= 5.0)
        assert far is True
        assert robot.time() - t0 == 2.0


@pytest.mark.asyncio
async def test_a_cancelled_wait_leaves_no_monitor_behind() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(1.0):
                await robot.wait("bumper", becomes=True)
        assert robot.events.monitors() == []


@pytest.mark.asyncio
async def test_monitor_wait_returns_the_value_of_the_next_firing() -> None:
    async with Robot() as robot:
        robot.state.ir = 1.0
        close = robot.whenever("ir", below=0.5)
        async with asyncio.TaskGroup() as tasks:
            tasks.create_task(_write_later(robot, 1.0, ir=0.25))
            assert await close.wait() == 0.25
        tasks_done = [asyncio.create_task(close.wait()) for _ in range(2)]
        await robot.sleep(0.05)
        robot.state.ir = 0.125  # still below: the level re-fires at 1.1 s, with the latest value
        robot.state.ir = 0.0625
        assert await asyncio.gather(*tasks_done) == [0.0625, 0.0625]
        assert close.firings == 2
        assert robot.time() == pytest.approx(1.1)


@pytest.mark.asyncio
async def test_waiting_on_a_stopped_monitor_raises() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        monitor = robot.whenever("bumper", becomes=True)
        waiter = asyncio.create_task(monitor.wait())
        await robot.sleep(0.1)
        monitor.stop_monitoring()
        with pytest.raises(StateError) as error:
            await waiter
        assert str(error.value) == "monitor 'bumper becomes=True' stopped before it fired"
        with pytest.raises(StateError) as again:
            await monitor.wait()
        assert str(again.value) == (
            "monitor 'bumper becomes=True' is stopped; it will not fire again"
        )


@pytest.mark.asyncio
async def test_on_fires_once_then_stops_monitoring() -> None:
    calls: list[float] = []
    async with Robot() as robot:
        robot.state.bumper = False
        t0 = robot.time()
        monitor = robot.on("bumper", becomes=True).do(lambda: calls.append(robot.time() - t0))
        for _ in range(3):
            robot.state.bumper = True
            await robot.sleep(0.5)
            robot.state.bumper = False
            await robot.sleep(0.5)
        assert (monitor.firings, monitor.monitoring, monitor.one_shot) == (1, False, True)
        assert robot.events.monitors() == []
    assert calls == [0.0]


@pytest.mark.asyncio
async def test_on_with_a_level_that_holds_fires_once() -> None:
    async with Robot() as robot:
        robot.state.battery = 0.1
        monitor = robot.on("battery", below=0.2)
        waited = await monitor.wait()
        await robot.sleep(10)
        assert (waited, monitor.firings) == (0.1, 1)


@pytest.mark.asyncio
async def test_the_monitors_listing_and_repr() -> None:
    async with Robot() as robot:
        robot.state.bumper = False
        assert repr(robot.events) == "<EventManager 0 monitors>"
        monitor = robot.whenever("bumper", becomes=True).do(print)
        assert repr(monitor) == (
            f"<EventMonitor #{monitor.id} 'bumper becomes=True' monitoring, "
            "fired 0, callback print>"
        )
        robot.every("bumper", value=True, max_firing_freq=2)
        assert len(robot.events) == 2
        assert [m.name for m in robot.events.monitors()] == [
            "bumper becomes=True",
            "bumper value=True",
        ]
        assert (monitor.var, monitor.condition, monitor.blocking) == (
            "bumper",
            "becomes=True",
            True,
        )
        assert robot.events.monitors()[1].max_firing_freq == 2.0
        robot.state.bumper = True  # the callback is queued: running
        assert repr(monitor) == (
            f"<EventMonitor #{monitor.id} 'bumper becomes=True' monitoring, fired 1, "
            "callback print running>"
        )
        monitor.stop_monitoring()
        assert repr(monitor) == (
            f"<EventMonitor #{monitor.id} 'bumper becomes=True' stopped, fired 1, "
            "callback print running>"
        )
