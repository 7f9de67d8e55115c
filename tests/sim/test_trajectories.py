"""The random walk's trajectories, pinned bit for bit (issue 15: speed without changing results).

Golden values were recorded on the code before the simulator was made faster;
every optimisation of the tick, the sensor read-out or the state store must
leave them unchanged. A fingerprint covers the final true pose and odometry,
the tick and step counts, the store's versions (a write of an unchanged value
is still a write), a digest of the whole state (value, timestamp, version of
every key) after every tick, and a digest of every ``robot.state`` sample the
recorder kept. (The recorder itself changed after the goldens were taken: it
now keeps every change instead of 10 samples a second, so only the sample
count and digest were taken anew, on the recorder of the replay-page work;
everything else is still the pre-optimisation golden run.)

If a change of the physics or of the walk is intended, print the new
fingerprints (``_fingerprint``) and replace the golden values, saying why in
the commit.
"""

from __future__ import annotations

import asyncio
import hashlib
from dataclasses import astuple, dataclass

import pytest

from pyrobots_aio.recording import MemoryRecorder
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.sim.random_walk import random_walk

pytestmark = [pytest.mark.asyncio, pytest.mark.virtual_time]

RECORDED_STATE = ("bumper", "bumper_left", "bumper_right", "docked", "v", "w")
"""The keys the demo records (``pyrobots-aio demo random-walk``)."""
MOVES = 6


@dataclass(frozen=True)
class Fingerprint:
    report: tuple[object, ...]
    base_pose: tuple[float, float, float]
    odom_pose: tuple[float, float, float]
    ticks: int
    steps: int
    store_version: int
    key_versions: tuple[tuple[str, int], ...]
    state_digest: str
    samples: int
    samples_digest: str


class _TickDigest:
    """Hashes the whole state (value, timestamp, version of every key) after every tick."""

    def __init__(self, robot: SimRobot) -> None:
        self.robot = robot
        self.hash = hashlib.sha256()
        self.ticks = 0

    def __call__(self) -> bool:
        state = self.robot.state
        row = [(key, *astuple(state.sample(key))) for key in sorted(state)]
        self.hash.update(repr((self.robot.time(), row)).encode())
        self.ticks += 1
        return False  # never done: called after every tick until cancelled


async def _fingerprint(seed: int) -> Fingerprint:
    robot = SimRobot(seed=seed)
    with MemoryRecorder(state_keys=RECORDED_STATE).attach(robot) as recorder:
        async with robot:
            digest = _TickDigest(robot)
            watcher = asyncio.create_task(robot.sim.control(digest))
            report = await random_walk(robot, moves=MOVES, seed=seed)
            watcher.cancel()
            with pytest.raises(asyncio.CancelledError):
                await watcher
            state = robot.state
            versions = tuple((key, state.version(key)) for key in sorted(state))
            fingerprint = (
                astuple(report),
                robot.world.base_pose(),
                robot.world.odom_pose(),
                robot.sim.ticks,
                robot.world.steps,
                state.version(),
                versions,
            )
            assert digest.ticks == robot.sim.ticks  # the digest saw every tick
    recording = recorder.recording()
    samples = [
        (time, key, repr(value))
        for key in RECORDED_STATE
        for time, value in zip(
            recording.samples[key].times, recording.samples[key].values, strict=True
        )
    ]
    return Fingerprint(
        *fingerprint,
        state_digest=digest.hash.hexdigest(),
        samples=len(samples),
        samples_digest=hashlib.sha256(repr(samples).encode()).hexdigest(),
    )


STATE_KEYS = (
    "battery",
    "bumper",
    "bumper_left",
    "bumper_right",
    "cliff_front_left",
    "cliff_front_right",
    "cliff_side_left",
    "cliff_side_right",
    "docked",
    "encoder_left",
    "encoder_right",
    "imu_acc_x",
    "imu_acc_y",
    "imu_gyro_z",
    "ir_front_center_left",
    "ir_front_center_right",
    "ir_front_left",
    "ir_front_right",
    "ir_left",
    "ir_right",
    "ir_side_left",
    "v",
    "w",
)


def _every_key(versions: int) -> tuple[tuple[str, int], ...]:
    """Every key written once at start and once per tick."""
    return tuple((key, versions) for key in STATE_KEYS)


# Recorded on commit 8e7e2b3 (before issue 15's changes). Seed 0 bumps three times,
# seed 12 once.
GOLDEN: dict[int, Fingerprint] = {
    0: Fingerprint(
        report=(6, 3, 3, True, 60.08),
        base_pose=(-1.7173775469104908, 0.007504056495766734, 0.002119533669583521),
        odom_pose=(0.009048913256237448, 0.007766521910319529, 0.001693656865752221),
        ticks=3004,
        steps=30040,
        store_version=3005,
        key_versions=_every_key(3005),
        state_digest="e1938f850d44a1b534acc0efdb41c8e2ac0817de9b8ead797dcf5ba9fce2355c",
        samples=5600,
        samples_digest="773a0e6e54b2d0e44d9e6da922c55e588e1db2c9b05788ca09c7e34256c3e86f",
    ),
    12: Fingerprint(
        report=(6, 1, 1, True, 56.88),
        base_pose=(-1.71778504046456, -0.007257512222567786, -0.0018949609270318749),
        odom_pose=(5.179186927485916e-05, -0.0031365982791474742, 0.004421141103769181),
        ticks=2844,
        steps=28440,
        store_version=2845,
        key_versions=_every_key(2845),
        state_digest="c4f1b8f6b0c235454d32dc6931bac0bb58c528d157c3b78f0b08df46559f3409",
        samples=5269,
        samples_digest="cb30cf5fc95caec35d014a3a1e6afd5d258d553cb3c4c450b29eb2086b3274f0",
    ),
}


@pytest.mark.parametrize("seed", sorted(GOLDEN))
async def test_the_random_walk_is_bit_identical_to_the_golden_run(seed: int) -> None:
    assert await _fingerprint(seed) == GOLDEN[seed]
