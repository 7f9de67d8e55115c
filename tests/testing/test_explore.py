"""Explore: a planted bug is found, shrunk to one hit, printed as code that replays it.

The planted bug is the Create 3 script's: a walk whose bump reflex is not
armed while it undocks. A held bump then meets no reflex, and the undock
drives on into it. Exploring must find that within a CI-sized budget, shrink
it to that one bump, and print code that, run, fails the same way.
"""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import ActionInterrupted, InvariantViolation
from pyrobots_aio.recording import load
from pyrobots_aio.sim.random_walk import bumper_reflex
from pyrobots_aio.testing import FakeBase
from pyrobots_aio.testing.explore import (
    At,
    Bump,
    Disturbance,
    Hit,
    Scenario,
    Target,
    completes,
    no_forward_into_bumper,
)

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    Walk = Callable[[FakeBase], Awaitable[None]]

pytest_plugins = ["pytester"]


async def careless_walk(robot: FakeBase) -> None:
    """Undock, then arm the reflex (too late), and drive out."""
    await robot.undock()
    await _drive_out(robot)


async def armed_walk(robot: FakeBase) -> None:
    """The fix: the reflex is armed before the undock."""
    await _drive_out(robot, robot.undock)


async def _drive_out(robot: FakeBase, first: Callable[[], Awaitable[None]] | None = None) -> None:
    reflex = robot.whenever("bumper", becomes=True).do(bumper_reflex)
    try:
        with contextlib.suppress(ActionInterrupted):  # the reflex took over
            if first is not None:
                await first()
            await robot.drive_distance(0.3)
    finally:
        await reflex.close()


def careless(
    behaviour: Callable[[FakeBase], Awaitable[None]] = careless_walk,
) -> Scenario[FakeBase]:
    return Scenario(
        behaviour,
        base=FakeBase,
        disturbances=[Bump],
        boundaries=["undock", "drive_distance"],
        invariants=[completes(), no_forward_into_bumper()],
        horizon=5.0,
        name="walk",
    )


FOUND = """\
walk broke its invariants under 1 hit(s):
  - at t=0.220 the base was commanded forward (v=0.200 m/s) with the front bumper pressed \
since t=0.000 (more than 0.2 s)
replay it in a test:

from pyrobots_aio.testing.explore import At, Bump, Hit
walk.replay([
    Hit(Bump(hold=0.5), At(0.0)),
])
"""


def test_the_unarmed_undock_is_found_and_shrunk_to_one_bump(tmp_path: Path) -> None:
    with pytest.raises(InvariantViolation) as found:
        careless().explore(examples=100, record_dir=tmp_path)
    message = str(found.value)
    assert message.startswith(FOUND)
    assert found.value.schedule == (Hit(Bump(hold=0.5), At(0.0)),)  # as it leaves the dock
    recording, page = tmp_path / "walk.jsonl", tmp_path / "walk.html"
    assert message.endswith(f"\nrecording: {recording}\nreplay page: {page}")
    assert load(recording).samples["disturbance"].values == ["Bump(hold=0.5)"]
    html = page.read_text(encoding="utf-8")  # its map marks the hit where the robot was
    assert re.search(r'<path class="mark disturbance" transform="translate\([\d.]+,[\d.]+\)"', html)
    assert "<title>disturbance: Bump(hold=0.5) at 0.000 s</title>" in html


def test_the_printed_code_replays_the_failure() -> None:
    with pytest.raises(InvariantViolation) as found:
        careless().explore(examples=100)
    code = str(found.value).split("replay it in a test:\n\n")[1].split("\nrecording:")[0]
    with pytest.raises(InvariantViolation) as replayed:
        exec(code, {"walk": careless()})
    assert replayed.value.violations == found.value.violations


def test_the_fixed_walk_replays_clean() -> None:
    run = careless(armed_walk).replay([Hit(Bump(hold=0.5), At(0.0))])
    assert (run.violations, run.error, [hit for _, hit in run.hits]) == (
        [],
        None,
        [Hit(Bump(hold=0.5), At(0.0))],
    )


PLANTED = """
    import pytest
    from pyrobots_aio.testing import FakeBase
    from pyrobots_aio.testing.explore import Bump, Scenario, no_forward_into_bumper

    async def careless_walk(robot):
        await robot.undock()  # no reflex at all

    @pytest.mark.explore(examples=30)
    def test_walk(explore):
        explore(Scenario(careless_walk, base=FakeBase, disturbances=[Bump], horizon=5.0,
                         invariants=[no_forward_into_bumper()], name="walk"))
"""


def test_the_fixture_explores_with_the_marker_and_records_into_tmp_path(
    pytester: pytest.Pytester,
) -> None:
    pytester.makeini(
        "[pytest]\nasyncio_mode = strict\nasyncio_default_fixture_loop_scope = function\n"
    )
    pytester.makepyfile(textwrap.dedent(PLANTED))
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--explore-profile=ci")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "E * walk broke its invariants under 1 hit(s):",
            "E * walk.replay([",
            "E *     Hit(Bump(hold=0.5), At(0.0)),",
            "E * recording: */test_walk0/walk.jsonl",
            "E * replay page: */test_walk0/walk.html",
        ]
    )


def test_a_bad_profile_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match=r"^the explore profile must be one of \['ci', 'dev', "):
        careless().explore(examples=1, profile="fast")


def test_without_hypothesis_explore_says_which_extra_to_install() -> None:
    code = (
        "import sys; sys.modules['hypothesis'] = None\n"
        "import pyrobots_aio.testing\n"  # the rest of the testing package needs no Hypothesis
        "try:\n"
        "    import pyrobots_aio.testing.explore\n"
        "except ImportError as missing:\n"
        "    print(type(missing).__name__, missing)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout == (
        "ExploreUnavailableError pyrobots_aio.testing.explore needs Hypothesis: "
        'pip install "pyrobots-aio[explore]" (or pip install -e ".[explore]" in a checkout)\n'
    )


def test_workers_split_the_search_and_find_the_same_bug_every_time() -> None:
    found = []
    for _ in range(2):
        with pytest.raises(InvariantViolation) as failure:
            careless().explore(examples=100, workers=2)
        found.append(failure.value.schedule)
    assert found[0] == found[1]
    assert len(found[0]) == 1


@dataclass(frozen=True, slots=True, repr=False)
class Broken(Disturbance):
    def apply(self, target: Target) -> None:
        raise ValueError("this disturbance cannot be applied")


@pytest.mark.parametrize("workers", [1, 2])
def test_a_disturbance_that_raises_is_raised_not_taken_for_a_violation(workers: int) -> None:
    scenario = Scenario(armed_walk, base=FakeBase, disturbances=[Broken()], horizon=1.0)
    with pytest.raises(ValueError, match=r"^this disturbance cannot be applied$"):
        scenario.explore(examples=5, workers=workers)


COUNTED = """
import sys
sys.path.insert(0, {tests!r})
from test_explore import careless
from pyrobots_aio import InvariantViolation

scenario = careless()
runs = []
fails = scenario._fails
scenario._fails = lambda schedule: runs.append(schedule) or fails(schedule)
try:
    scenario.explore(examples=100, profile="dev")
except InvariantViolation as found:
    print(len(runs), found.schedule)
"""


def test_under_dev_a_failure_is_kept_and_tried_first_at_the_next_run(tmp_path: Path) -> None:
    script = tmp_path / "count.py"
    script.write_text(COUNTED.format(tests=str(Path(__file__).parent)))

    def explore() -> tuple[int, str]:
        done = subprocess.run(
            [sys.executable, str(script)],
            capture_output=True, text=True, check=True, timeout=300, cwd=tmp_path,
        )  # fmt: skip
        runs, schedule = done.stdout.split(" ", 1)
        return int(runs), schedule

    first, again = explore(), explore()
    assert (tmp_path / ".hypothesis" / "examples").is_dir()
    assert again[1] == first[1]
    assert again[0] < first[0]  # the saved example first, then a shorter shrink
