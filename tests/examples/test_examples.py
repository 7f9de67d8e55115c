from __future__ import annotations

import ast
import importlib.util
import math
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

from pyrobots_aio import EventKind, Outcome
from pyrobots_aio.testing import EventLog

EXAMPLES = Path(__file__).parent.parent.parent / "examples"


def load_example(name: str) -> ModuleType:
    """Import ``examples/<name>.py`` as a module (without running its ``__main__`` part)."""
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def main_block_calls(name: str) -> list[str]:
    """The names of the functions ``examples/<name>.py`` calls in its ``__main__`` block."""
    tree = ast.parse((EXAMPLES / f"{name}.py").read_text())
    blocks = [
        node
        for node in tree.body
        if isinstance(node, ast.If) and "__main__" in ast.unparse(node.test)
    ]
    assert len(blocks) == 1, f"examples/{name}.py needs one 'if __name__ == \"__main__\":' block"
    calls = (n for n in ast.walk(blocks[0]) if isinstance(n, ast.Call))
    return [ast.unparse(call.func) for call in calls]


@pytest.mark.parametrize(
    "name", sorted(p.stem for p in EXAMPLES.glob("*.py") if p.stem != "run_all")
)
def test_example_installs_the_console_handler(name: str) -> None:
    calls = main_block_calls(name)
    assert "install_console_handler" in calls
    assert "logging.basicConfig" not in calls


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_safe_walk_awaits_its_cleanup_before_it_is_done() -> None:
    log = EventLog()
    assert await load_example("safe_walk").main(instruments=[log]) is Outcome.CANCELLED
    stop = log.first(EventKind.CANCEL_REQUESTED, "safe_walk").time
    finished = [(e.name, e.data["outcome"], e.time) for e in log.of_kind(EventKind.ACTION_FINISHED)]
    # the rest pose (0.2 s) ran to completion, then safe_walk finished, re-raising the cancellation
    assert finished == [
        ("walk", "cancelled", stop),
        ("go_back_to_rest_pose", "succeeded", pytest.approx(stop + 0.2)),
        ("safe_walk", "cancelled", pytest.approx(stop + 0.2)),
    ]
    rest = log.first(EventKind.ACTION_SPAWNED, "go_back_to_rest_pose")
    assert rest.data["parent"] == log.first(EventKind.ACTION_SPAWNED, "safe_walk").action


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_resources() -> None:
    outcomes = await load_example("resources").main()
    assert outcomes == {
        "lift_box": Outcome.SUCCEEDED,
        "wave_hand": Outcome.SUCCEEDED,
        "scratch_head": Outcome.SKIPPED,
        "long_lift_box": Outcome.CANCELLED,
        "catch_falling_cup": Outcome.SUCCEEDED,
    }


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_look_at() -> None:
    pan, tilt, x, y = await load_example("look_at").main()
    assert pan == pytest.approx(math.pi / 2)
    assert tilt == pytest.approx(math.pi / 4)
    assert (x, y) == (pytest.approx(0.0, abs=1e-12), pytest.approx(2.0))


@pytest.mark.asyncio
async def test_embedded() -> None:
    module: ModuleType = load_example("embedded")
    started, running, missing, after = await module.main()
    assert started == {"started": 1}
    assert running == [{"id": 1, "name": "patrol", "state": "running", "parent": None}]
    assert missing == {"error": "no route GET /nope"}
    assert after == []


@pytest.mark.asyncio
async def test_embedded_fastapi() -> None:
    seen = await load_example("embedded_fastapi").try_it()
    patrol = {"id": 1, "name": "patrol"}
    assert seen["started"] == {**patrol, "state": "pending", "outcome": "not_done"}
    assert seen["gave up"] == {**patrol, "state": "running", "outcome": "not_done"}
    levels = seen["battery"]  # the level, then two changes of one percent
    assert levels == [levels[0], round(levels[0] - 0.01, 2), round(levels[0] - 0.02, 2)]
    owned = {"id": 2, "name": "dock", "cancel_reason": "the task awaiting it was cancelled"}
    late = {"error": "not done within 0.2 s", **owned, "state": "cancelling", "outcome": "not_done"}
    assert seen["late"] == {"detail": late}  # a 504: the deadline cancelled the owned action
    assert seen["late after"] == {**owned, "state": "done", "outcome": "cancelled"}
    assert seen["simulated"]["outcome"] == "succeeded"
    assert seen["stop"] == {"stopped": 1}
    assert seen["stopped"] == {
        **patrol,
        "state": "done",
        "outcome": "cancelled",
        "cancel_reason": "stop button",
    }
    short = {"id": 3, "name": "patrol"}
    assert seen["short after"] == {**short, "state": "done", "outcome": "succeeded", "result": 2}


@pytest.mark.asyncio
async def test_embedded_aiohttp() -> None:
    seen = await load_example("embedded_aiohttp").try_it()
    vacuum = {"id": 1, "name": "vacuum"}
    assert seen["gave up"] == {**vacuum, "state": "running", "outcome": "not_done"}
    levels = seen["battery"]
    assert levels == [levels[0], round(levels[0] - 0.01, 2), round(levels[0] - 0.02, 2)]
    assert seen["cancelled"] == {**vacuum, "state": "done", "outcome": "cancelled"}
    short = {"id": 2, "name": "vacuum"}
    assert seen["short after"] == {**short, "state": "done", "outcome": "succeeded", "result": 2}


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_master_controller() -> None:
    log = EventLog()
    report = await load_example("master_controller").main(instruments=[log])
    assert report == [
        "grasp_cup: cup grasped",
        "lift: cup lifted (attempt 3)",
        "fault (camera lost): no limb in use, motors off",
        "safe pose",
        "safe: pose safe, camera stale, no limb in use, motors off",
    ]
    # retries: each attempt of lift is a child of the retrying lift, after its backoff
    (retrying, *attempts) = log.of_kind(EventKind.ACTION_SPAWNED, "lift")
    assert [e.data["parent"] for e in attempts] == [retrying.action] * 3
    assert [e.time - retrying.time for e in attempts] == pytest.approx([0, 0.2 + 0.1, 0.5 + 0.2])
    assert log.outcomes("lift") == ["failed", "failed", "succeeded", "succeeded"]
    # the fault: the camera's last frame was at 74/30 s; stale 0.5 s later, the e-stop
    stop = log.first(EventKind.ACTION_SPAWNED, "emergency_stop")
    assert stop.time == pytest.approx(74 / 30 + 0.5)
    # the walk slipped at 2.2 s: its retry was waiting out its 1 s backoff, holding no limb,
    # when the stop cancelled it there; it never walked again
    (retrying_walk, walk_attempt) = log.of_kind(EventKind.ACTION_SPAWNED, "walk_to_table")
    assert walk_attempt.data["parent"] == retrying_walk.action
    assert log.first(EventKind.ACTION_FINISHED, "walk_to_table").time == pytest.approx(2.2)
    walk = log.assert_cancelled("walk_to_table", by="emergency_stop", after=stop.time, within=0)
    assert walk.action == retrying_walk.action
    assert walk.data["reason"] == "emergency stop: camera lost"
    assert log.outcomes("walk_to_table") == ["failed", "cancelled"]
    # every action holding a limb at the e-stop ended before the recovery took the safe pose
    events = log.events
    safe_pose = events.index(log.first(EventKind.ACTION_STARTED, "go_to_safe_pose"))
    acquired = {
        e.action for e in events[: events.index(stop)] if e.kind is EventKind.RESOURCE_ACQUIRED
    }
    released = {e.action for e in events[:safe_pose] if e.kind is EventKind.RESOURCE_RELEASED}
    assert acquired <= released
    # the phases: the machine's states are its children; the stop ended the plan, and the
    # machine took its failure path (plan -> recover on FAILED): the recovery worked
    master = log.first(EventKind.ACTION_SPAWNED, "master").action
    phases = [e.name for e in log.of_kind(EventKind.ACTION_SPAWNED) if e.data["parent"] == master]
    assert phases == ["execute_plan", "recover"]
    plan = log.assert_cancelled("execute_plan", by="emergency_stop", after=stop.time, within=0)
    assert plan.data["reason"] == "emergency stop: camera lost"
    assert log.outcomes("execute_plan") == ["cancelled"]
    assert log.outcomes("master") == ["succeeded"]
    assert log.outcomes("go_to_safe_pose") == ["succeeded"]
    spawned_since = [
        e.name for e in events[events.index(stop) :] if e.kind is EventKind.ACTION_SPAWNED
    ]
    assert spawned_since == ["emergency_stop", "recover", "go_to_safe_pose"]
    assert log.outcomes("health_monitor") == ["cancelled"]  # it ran until the robot's exit


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_random_walk_completes_with_every_bump_handled() -> None:
    report = await load_example("random_walk").main(seed=3)
    assert report.moves == 10
    assert report.bumps >= 1
    assert report.interrupted >= 1
    assert report.docked


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_kindergarten_session() -> None:
    session = await load_example("kindergarten").main(minutes=5, seed=1)
    assert session.minutes == 5
    assert session.reactions["look"] == 5 * 60  # one per second of the session
    assert session.reactions["blink"] > 5 * 60 / 6
    assert session.reactions["giggle"] > 0
    assert session.reactions["cry"] + session.reactions["thank"] > 0
    # every monitor firing (an event) started exactly one reaction
    monitored = ("cry", "thank", "giggle", "hello", "back_off")
    assert session.events_per_minute * 5 == sum(session.reactions[r] for r in monitored)
    # pinned for seed 1: the robot's moves (so the bumper and IR events) come from the simulator
    assert (session.actions_per_minute, session.peak_actions_per_minute) == (100.0, 118)
    assert (session.events_per_minute, session.peak_events_per_minute) == (8.0, 18)
    assert session.cap_hits == 0
    assert session.refused == {}


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_kindergarten_safety_cap_refuses_and_counts() -> None:
    session = await load_example("kindergarten").main(minutes=2, seed=1, max_actions=3)
    # blink, look_at_child and wander fill the three slots for the whole session, so every
    # other start is refused: each look (one a second for 120 s), each blink, each of wander's
    # moves (it cannot even undock, so the bumper and the IR sensors never fire) and each
    # reaction of the toy and pacifier monitors (14 squeezes, the pacifier taken once)
    assert session.refused == {"look": 120, "blink": 33, "move": 11, "giggle": 14, "cry": 1}
    assert session.cap_hits == 179
    assert session.reactions == {}
    assert session.events_per_minute * 2 == session.refused["giggle"] + session.refused["cry"]
    assert (session.actions_per_minute, session.peak_actions_per_minute) == (1.5, 3)
    assert (session.events_per_minute, session.peak_events_per_minute) == (7.5, 12)


NO_RCLPY = """
import sys


class NoRclpy:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] == "rclpy":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)


sys.meta_path.insert(0, NoRclpy())
"""


@pytest.mark.parametrize("external", [False, True])
def test_random_walk_ros2_without_rclpy_says_so_without_a_traceback(
    tmp_path: Path, external: bool
) -> None:
    # Before: the clean error, then a 48-line traceback. The sitecustomize hides rclpy
    # from the example and from the sim-node it starts.
    (tmp_path / "sitecustomize.py").write_text(NO_RCLPY)
    path = os.pathsep.join(p for p in (str(tmp_path), os.environ.get("PYTHONPATH")) if p)
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / "random_walk_ros2.py"), *(["--external"] * external)],
        env={**os.environ, "PYTHONPATH": path, "ROS_DOMAIN_ID": "0"},
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    needs = (
        "the ROS 2 bridge needs rclpy, which cannot be imported (No module named 'rclpy'); "
        'install the ROS 2 Python wheels with: pip install "pyrobots-aio[ros2]", or source a '
        "ROS 2 install"
    )
    assert (done.returncode, done.stdout) == (1, "")
    if external:
        assert done.stderr == f"random_walk_ros2.py: error: {needs}\n"
    else:  # the sim-node says why it did not start, the example that it did not
        assert done.stderr == (
            f"pyrobots-aio: error: {needs}\n"
            "random_walk_ros2.py: error: the sim-node did not start (exit 1)\n"
        )


@pytest.mark.parametrize("name", ["kindergarten", "random_walk_ros2", "create3_walk"])
def test_every_option_of_an_example_has_help(name: str) -> None:
    tree = ast.parse((EXAMPLES / f"{name}.py").read_text())
    options = [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and ast.unparse(node.func).endswith(".add_argument")
    ]
    assert options
    assert [
        ast.unparse(o.args[0]) for o in options if "help" not in {k.arg for k in o.keywords}
    ] == []
