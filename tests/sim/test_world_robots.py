"""Several robots in one simulated world: one physics, their own docks, bumping into each other."""

from __future__ import annotations

import asyncio
import math
import re

import pytest

from pyrobots_aio.sim import SimRobot, SimWorld

TICK_STEPS = 10  # one 50 Hz control tick of 2 ms physics steps
DOCKED_X = -1.728  # where the scene's keyframe puts a docked robot


def drive_until_bumped(world: SimWorld, driver: SimWorld, limit: float = 3.0) -> None:
    """Step ``world`` a tick at a time until ``driver``'s bumper is pressed (within ``limit`` s)."""
    for _ in range(round(limit / (TICK_STEPS * world.physics_dt))):
        world.step(TICK_STEPS)
        if driver.read_sensors()["bumper"]:
            return
    pytest.fail(f"{driver!r} never bumped into anything in {limit} s")


def test_each_robot_starts_on_its_own_dock_half_a_metre_from_the_next() -> None:
    world = SimWorld(robots=3)
    assert world.robots[0] is world
    assert [round(r.base_pose()[1], 6) for r in world.robots] == [0.0, 0.5, -0.5]
    assert {round(r.base_pose()[0], 6) for r in world.robots} == {DOCKED_X}
    assert [r.read_sensors()["docked"] for r in world.robots] == [True, True, True]
    docks = [r.frame_planar("dock") for r in world.robots]
    assert [(round(x, 6), round(y, 6)) for x, y, _ in docks] == [
        (-1.9, 0.0),
        (-1.9, 0.5),
        (-1.9, -0.5),
    ]
    assert [s["name"] for s in world.floor_plan() if s["kind"] == "dock"] == [
        "dock",
        "robot2/dock",
        "robot3/dock",
    ]
    assert repr(world.robots[1]) == "<SimWorld scene.xml robot 2 of 3 seed=0 t=0.000s>"
    assert repr(SimWorld()) == "<SimWorld scene.xml seed=0 t=0.000s>"
    assert world.robots[2].frame_names == world.frame_names
    assert world.robots[2].state_keys == world.state_keys


def test_one_physics_each_robot_obeys_its_own_command() -> None:
    world = SimWorld(robots=2)
    first, second = world.robots
    second.set_command(0.2, 0.0)
    second.advance(1.0)  # stepping either robot steps the one physics
    assert (first.steps, first.time, second.time) == (500, 1.0, 1.0)
    assert first.odom_pose() == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert first.read_sensors()["docked"] is True
    assert second.odom_pose()[0] == pytest.approx(0.19, abs=0.01)
    assert second.read_sensors()["docked"] is False
    assert (first.command, second.command) == ((0.0, 0.0), (0.2, 0.0))
    first.set_time(7.0)
    assert second.time == 7.0  # one clock


def test_placing_one_robot_leaves_the_others_moving() -> None:
    world = SimWorld(robots=2)
    first, second = world.robots
    first.set_command(0.2, 0.0)
    world.advance(1.0)
    moving = first.read_sensors()["v"]
    second.place(0.0, 1.0, 0.0)
    assert first.read_sensors()["v"] == moving
    assert second.read_sensors()["v"] == 0.0


def test_robots_facing_each_other_see_and_bump_into_each_other() -> None:
    world = SimWorld(robots=2)
    first, second = world.robots
    first.place(0.0, 0.0, 0.0)
    second.place(0.6, 0.0, math.pi)  # 0.258 m of floor between their shells
    world.step(TICK_STEPS)
    seen = first.read_sensors()["ir_front_center_left"]
    assert seen == pytest.approx(0.6 - 0.171 - 0.1644, abs=0.01)  # the other's shell
    first.set_command(0.2, 0.0)
    drive_until_bumped(world, first)
    mine, theirs = first.read_sensors(), second.read_sensors()
    assert (mine["bumper_left"], mine["bumper_right"]) == (True, True)  # head on
    assert (theirs["bumper_left"], theirs["bumper_right"]) == (True, True)
    assert math.dist(first.base_pose()[:2], second.base_pose()[:2]) == pytest.approx(
        2 * 0.171, abs=0.005
    )


def test_the_same_seed_gives_the_same_world_and_each_robot_its_own_noise() -> None:
    def run() -> list[object]:
        world = SimWorld(robots=2, seed=4)
        first, second = world.robots
        first.place(0.0, 0.0, 0.0)
        second.place(0.6, 0.0, math.pi)
        world.step(TICK_STEPS)
        return [r.read_sensors()["ir_front_center_left"] for r in world.robots]

    readings = run()
    assert readings == run()
    assert readings[0] != readings[1]  # the same distance, different noise


@pytest.mark.parametrize("robots", [0, 8, -1, True, 2.0, "2"])
def test_a_bad_number_of_robots_is_refused(robots: object) -> None:
    message = f"robots must be a whole number from 1 to 7 (one dock each), not {robots!r}"
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        SimWorld(robots=robots)  # type: ignore[arg-type]


def test_a_robot_of_a_world_takes_the_world_s_model_and_seed() -> None:
    world = SimWorld(robots=2, seed=3)
    assert SimRobot(world=world.robots[1]).seed == 3
    message = (
        "SimRobot(world=...) takes its model, seed and physics_dt from the world; "
        "pass them to SimWorld(...) instead"
    )
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        SimRobot(world=world.robots[1], seed=3)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_two_simulated_robots_in_one_program_the_first_drives_into_the_second() -> None:
    world = SimWorld(robots=2)
    first, second = (SimRobot(world=w) for w in world.robots)
    async with first:
        await asyncio.sleep(0.5)  # the second joins a running world
        async with second:
            loop = asyncio.get_running_loop()
            assert world.time == pytest.approx(loop.time(), abs=0.02)
            await asyncio.gather(first.drive_distance(0.5), second.drive_distance(0.5))
            await first.rotate_angle(math.pi / 2)  # facing the second's right side
            first.drive(0.1, 0.0)
            async with asyncio.timeout(5):
                await first.wait("bumper", value=True)
            first.stop()
            gap = second.map_pose()[1] - first.map_pose()[1]
            assert gap == pytest.approx(2 * 0.171, abs=0.01)
            assert second.state.docked is False
            assert world.time == first.time() == second.time()
