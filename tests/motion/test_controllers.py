"""Controllers, the per-tick bookkeeping a base runs, and what DriveBase asks of a base."""

from __future__ import annotations

import asyncio

import pytest

from pyrobots_aio import DriveBase, MotionError
from pyrobots_aio.motion import Controllers


@pytest.mark.asyncio
async def test_each_step_runs_once_per_update_until_it_is_done() -> None:
    controllers, calls = Controllers(), {"a": 0, "b": 0}

    def step(name: str, until: int) -> bool:
        calls[name] += 1
        return calls[name] == until

    a = asyncio.ensure_future(controllers.control(lambda: step("a", 2)))
    b = asyncio.ensure_future(controllers.control(lambda: step("b", 4)))
    await asyncio.sleep(0)
    for _ in range(6):
        controllers.run()
        await asyncio.sleep(0)
    assert (a.done(), b.done(), calls) == (True, True, {"a": 2, "b": 4})
    assert len(controllers) == 0


@pytest.mark.asyncio
async def test_a_failing_step_ends_its_own_wait_only() -> None:
    controllers = Controllers()

    def broken() -> bool:
        raise MotionError("wheel jammed")

    failing = asyncio.ensure_future(controllers.control(broken))
    waiting = asyncio.ensure_future(controllers.control(lambda: False))
    await asyncio.sleep(0)
    controllers.run()
    with pytest.raises(MotionError, match="wheel jammed"):
        await failing
    assert not waiting.done()
    controllers.fail(MotionError("odometry is stale"))
    with pytest.raises(MotionError, match="odometry is stale"):
        await waiting
    assert repr(controllers) == "<Controllers waiting=0>"


@pytest.mark.asyncio
async def test_cancel_ends_every_wait_and_a_cancelled_wait_leaves() -> None:
    controllers = Controllers()
    left = asyncio.ensure_future(controllers.control(lambda: False))
    stays = asyncio.ensure_future(controllers.control(lambda: False))
    await asyncio.sleep(0)
    left.cancel()
    await asyncio.sleep(0)
    assert len(controllers) == 1
    controllers.cancel()
    with pytest.raises(asyncio.CancelledError):
        await stays
    assert len(controllers) == 0


def test_a_base_must_be_given_a_whole_drive_backend() -> None:
    class Half:
        def set_velocity(self, v: float, w: float) -> None:
            pass

        async def start(self, robot: object) -> None:
            pass

        async def stop(self) -> None:
            pass

    with pytest.raises(TypeError) as caught:
        DriveBase(backend=Half())  # type: ignore[arg-type]
    assert str(caught.value).startswith("a DriveBase needs a DriveBackend; <")
    assert str(caught.value).endswith(
        " lacks sensors, frames, control_period, odom_pose, map_pose, control "
        "(see pyrobots_aio.motion.DriveBackend)"
    )
