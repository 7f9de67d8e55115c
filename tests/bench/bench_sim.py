"""Benchmarks of the simulated robot: the lockstep walk against its physics limit (DESIGN.md §10).

The limit is the same model at the same rates (50 Hz control, 2 ms physics)
stepped by a bare loop: ``mj_step`` ten times, then every sensor read into a
dict through precomputed ``sensordata`` addresses. It replays the wheel
commands of the product's walk tick by tick (captured in a run that is not
timed), so it steps through the very same physics, contacts and bumps: its
final pose is checked to equal the product's bit for bit.

The product is the full lockstep random walk (`WALK_SECONDS` of moves, then
docking): `SimRobot`, the executive, the walk's bumper monitor, and a
`JsonlRecorder` writing the demo's state keys to a temporary file, as
``pyrobots-aio demo random-walk --record`` does; timed from entering
``async with robot`` to leaving it (not the model's loading).

Both report simulated seconds per wall-clock second. On a shared 2-core
machine the two are interleaved (limit, product, limit, product ...), and the
ratio is the median of the ratios of adjacent pairs, which see the same load;
the same is given on thread CPU time (``time.thread_time``), which other
processes disturb less. The idle figures (a docked robot sleeping) are the
best of three runs, on thread CPU time.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import mujoco

from pyrobots_aio.loops import run_lockstep
from pyrobots_aio.recording import JsonlRecorder
from pyrobots_aio.sim import SimRobot, SimWorld
from pyrobots_aio.sim.random_walk import random_walk

IDLE_SECONDS = 120.0
WALK_SECONDS = 120.0
WALK_SEED = 1
ROUNDS = 7
RECORDED_STATE = ("bumper", "bumper_left", "bumper_right", "docked", "v", "w")
"""The state keys ``pyrobots-aio demo random-walk`` records."""


def _tick_cost() -> dict[str, float]:
    """One control tick of SimWorld, and, as a yardstick, ten bare mj_step of the same model."""
    world = SimWorld()
    world.set_command(0.2, 0.3)
    ticks = 2_000
    start = time.perf_counter()
    for _ in range(ticks):
        world.step(10)
        world.read_sensors()
    physics = (time.perf_counter() - start) / ticks
    model, data = world._model, world._data
    start = time.perf_counter()
    for _ in range(ticks):
        mujoco.mj_step(model, data, nstep=10)
    bare = (time.perf_counter() - start) / ticks
    return {"physics_tick_us": physics * 1e6, "bare_mj_step_x10_us": bare * 1e6}


async def _idle() -> float:
    """Thread CPU seconds for a docked robot to sleep `IDLE_SECONDS` in lockstep."""
    async with SimRobot() as robot:
        start = time.thread_time()
        await robot.sleep(IDLE_SECONDS)
        return time.thread_time() - start


# -- the product: the recorded lockstep walk ---------------------------------------------


class _Commands:
    """Keeps the wheel command each tick stepped with, and the final pose (for the limit)."""

    def __init__(self, robot: SimRobot) -> None:
        self.robot = robot
        self.ticks: list[list[float]] = []
        # Subscribers run inside the tick's state write: after its steps, before any
        # controller changes the command.
        self.subscription = robot.state.subscribe(self._on_tick)
        self.qpos: list[float] = []

    def _on_tick(self, changes: object) -> None:
        if self.robot.sim.ticks > len(self.ticks):
            self.ticks.append(self.robot.world._data.ctrl.tolist())
            self.qpos = self.robot.world._data.qpos.tolist()


async def _walk(
    path: Path, capture: bool, watchdog: bool = True
) -> tuple[float, float, float, _Commands | None]:
    """Run the walk; return (sim seconds, wall s, thread CPU s, the commands if captured).

    Without ``watchdog``, the robot has no loop watchdog thread (whose work follows the wall
    clock: `tests.bench.instructions` counts the walk without it).
    """
    robot = SimRobot(seed=WALK_SEED) if watchdog else SimRobot(seed=WALK_SEED, block_threshold=None)
    commands = _Commands(robot) if capture else None
    with JsonlRecorder(path, state_keys=RECORDED_STATE).attach(robot):
        wall, cpu = time.perf_counter(), time.thread_time()
        async with robot:
            report = await random_walk(robot, duration=WALK_SECONDS, seed=WALK_SEED)
        wall, cpu = time.perf_counter() - wall, time.thread_time() - cpu
    if commands is not None:
        commands.subscription.close()
    return report.sim_time, wall, cpu, commands


# -- the limit: a bare mj_step loop with sensor read-out --------------------------------


def _sensor_layout(model: mujoco.MjModel) -> list[tuple[str, int, int]]:
    return [
        (model.sensor(i).name, int(model.sensor_adr[i]), int(model.sensor_dim[i]))
        for i in range(model.nsensor)
    ]


def _limit(commands: _Commands) -> tuple[float, float, float]:
    """Step the bare model through ``commands``; return (sim seconds, wall s, thread CPU s)."""
    world = SimWorld(seed=WALK_SEED)  # for the model file and the docked start pose only
    model = mujoco.MjModel.from_xml_path(str(world.model_path))
    model.opt.timestep = world.physics_dt
    data = mujoco.MjData(model)
    data.qpos[:] = world._data.qpos
    mujoco.mj_forward(model, data)
    layout = _sensor_layout(model)
    steps = round(0.02 / world.physics_dt)  # 50 Hz control
    wall, cpu = time.perf_counter(), time.thread_time()
    for ctrl in commands.ticks:
        data.ctrl[:] = ctrl
        mujoco.mj_step(model, data, nstep=steps)
        values = data.sensordata.tolist()
        state = {
            name: values[adr] if dim == 1 else values[adr : adr + dim] for name, adr, dim in layout
        }
    wall, cpu = time.perf_counter() - wall, time.thread_time() - cpu
    assert len(state) == model.nsensor
    assert data.qpos.tolist() == commands.qpos  # the very same physics as the product's
    return len(commands.ticks) * steps * model.opt.timestep, wall, cpu


def _side_by_side() -> dict[str, float]:
    figures: dict[str, list[float]] = {
        k: [] for k in ("limit", "product", "ratio", "limit_cpu", "product_cpu", "ratio_cpu")
    }
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "walk.jsonl"
        sim_time, _, _, commands = run_lockstep(_walk, path, True)
        assert commands is not None
        for _ in range(ROUNDS):
            limit_sim, limit_wall, limit_cpu = _limit(commands)
            product_sim, product_wall, product_cpu, _ = run_lockstep(_walk, path, False)
            assert product_sim == sim_time  # the same walk every time
            for kind, sim, wall, cpu in (
                ("limit", limit_sim, limit_wall, limit_cpu),
                ("product", product_sim, product_wall, product_cpu),
            ):
                figures[kind].append(sim / wall)
                figures[f"{kind}_cpu"].append(sim / cpu)
            figures["ratio"].append(figures["product"][-1] / figures["limit"][-1])
            figures["ratio_cpu"].append(figures["product_cpu"][-1] / figures["limit_cpu"][-1])
    median = {key: statistics.median(values) for key, values in figures.items()}
    return {
        "random_walk_sim_seconds": sim_time,
        "sim_limit_realtime_factor": median["limit"],
        "random_walk_realtime_factor": median["product"],
        "random_walk_vs_limit": median["ratio"],
        "random_walk_vs_limit_cpu": median["ratio_cpu"],
    }


def run() -> dict[str, float]:
    """Measure the simulator; return the figures."""
    figures = _tick_cost()
    idle = min(run_lockstep(_idle) for _ in range(3))
    figures["control_tick_us_with_executive"] = idle / (IDLE_SECONDS * 50) * 1e6
    figures["idle_realtime_factor"] = IDLE_SECONDS / idle
    figures.update(_side_by_side())
    return figures


if __name__ == "__main__":
    for key, value in run().items():
        print(f"{key:34} {value:12.3f}")
