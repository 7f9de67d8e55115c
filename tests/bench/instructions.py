"""Instructions per awaited action and per bare task, counted by callgrind (load-independent).

``python -m tests.bench.instructions --walk [--src DIR ...]`` counts, instead, a
control tick of the recorded lockstep walk and of its limit (`bench_sim`: the
bare ``mj_step`` loop through the same commands), and their ratio (the limit's
instructions over the walk's, as `bench_sim`'s speed ratio is the walk's speed
over the limit's). Three runs each: the walk captured alone, then followed by
the limit, then by the walk again; the differences are what each costs.

``python -m tests.bench.instructions [--src DIR ...]``: for each source tree
(default: the installed package), the action start+finish of DESIGN.md §10
(``await nop(robot)``, one by one) and a bare ``await
asyncio.create_task(nop())`` run under ``valgrind --tool=callgrind``, twice
each: `SHORT` and `LONG` operations after the same warm-up; the difference
over ``LONG - SHORT`` is what one operation costs, start-up and warm-up
left out. Wall-clock ratios (``python -m tests.bench actions``) swing with the
machine's load; instruction counts do not (hash seed fixed, address
randomisation off where ``setarch`` allows, numpy's OpenBLAS on one thread:
its idle threads spin for as long as the run lasts), which makes them the figure to
compare two versions of the executive side by side. Needs valgrind; each run
takes a minute or two.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from pyrobots_aio import Robot, action

SHORT, LONG = 300, 5300
"""Operations of the two runs of each kind: their difference is what is counted."""
WARM_UP = 500
"""Actions and bare tasks run first in every run (caches, specialised bytecode)."""


@action
async def nop(robot: Robot) -> int:
    return 1


async def bare_nop() -> int:
    return 1


async def _workload(kind: str, count: int) -> None:
    async with Robot(block_threshold=None) as robot:  # no watchdog thread to count
        for _ in range(WARM_UP):
            await nop(robot)
            await asyncio.create_task(bare_nop())
        if kind == "action":
            for _ in range(count):
                await nop(robot)
        else:
            for _ in range(count):
                await asyncio.create_task(bare_nop())


def _instructions(src: str | None, kind: str, count: int) -> int:
    """Instructions callgrind counts for one run of ``count`` operations of ``kind``."""
    return _count(src, ["--run", kind, str(count)])[0]


def _count(src: str | None, args: list[str]) -> tuple[int, str]:
    """Instructions callgrind counts for one run of this module with ``args``, and its output."""
    # numpy's OpenBLAS threads spin while they wait: their count follows the wall clock
    threads = dict.fromkeys(("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"), "1")
    env = {**os.environ, "PYTHONHASHSEED": "0", **threads}
    if src is not None:
        env["PYTHONPATH"] = src
    command = [sys.executable, "-m", "tests.bench.instructions", *args]
    # --trace-children: the ROS 2 wheels' start-up hook (a .pth) may exec Python again
    valgrind = [
        "valgrind",
        "--tool=callgrind",
        "--trace-children=yes",
        "--cache-sim=no",
        "--callgrind-out-file=/dev/null",
    ]
    prefix = ["setarch", os.uname().machine, "-R"] if shutil.which("setarch") else []
    done = subprocess.run(
        [*prefix, *valgrind, *command], env=env, capture_output=True, text=True, check=True
    )
    found = re.findall(r"Collected : (\d+)", done.stderr)
    if not found:
        msg = f"callgrind printed no count:\n{done.stderr[-2000:]}"
        raise RuntimeError(msg)
    return int(found[-1]), done.stdout  # the Python that ran the workload (the last to end)


def _walk_workload(then: str) -> None:
    """Capture the walk's commands (a walk), then run ``then``: nothing, the limit, the walk."""
    from pyrobots_aio.loops import run_lockstep  # (the sim extra: only this mode needs it)

    from . import bench_sim

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "walk.jsonl"
        _, _, _, commands = run_lockstep(bench_sim._walk, path, True, False)
        assert commands is not None
        if then == "limit":
            bench_sim._limit(commands)
        elif then == "walk":
            run_lockstep(bench_sim._walk, path, False, False)
        print(len(commands.ticks))  # the ticks each counted run took


def per_tick(src: str | None) -> tuple[float, float]:
    """Instructions of one tick of (the walk, its limit) with the sources ``src``."""
    counts, ticks = {}, set()
    for then in ("nothing", "limit", "walk"):
        counts[then], out = _count(src, ["--walk-run", then])
        ticks.add(int(out.split()[-1]))
    (n,) = ticks  # the same walk every time
    return (counts["walk"] - counts["nothing"]) / n, (counts["limit"] - counts["nothing"]) / n


def per_operation(src: str | None, kind: str) -> float:
    """Instructions one operation of ``kind`` costs with the sources ``src`` (None: installed)."""
    return (_instructions(src, kind, LONG) - _instructions(src, kind, SHORT)) / (LONG - SHORT)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description="Instructions per awaited action and bare task.")
    parser.add_argument("--src", action="append", help="a src/ directory to measure (repeatable)")
    parser.add_argument("--walk", action="store_true", help="count the lockstep walk's tick")
    parser.add_argument("--run", nargs=2, metavar=("KIND", "COUNT"), help=argparse.SUPPRESS)
    parser.add_argument("--walk-run", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.run is not None:  # one run, under callgrind
        asyncio.run(_workload(args.run[0], int(args.run[1])))
        return 0
    if args.walk_run is not None:
        _walk_workload(args.walk_run)
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed; apt-get install valgrind", file=sys.stderr)
        return 1
    sources: list[str | None] = args.src or [None]
    if args.walk:
        print(f"{'sources':50} {'walk':>9} {'limit':>9} {'ratio':>7}")
        for src in sources:
            walk, limit = per_tick(src)
            name = str(Path(src).resolve()) if src is not None else "installed"
            print(f"{name:50} {walk:9.0f} {limit:9.0f} {limit / walk:7.3f}")
        return 0
    bare = per_operation(sources[0], "bare")  # (it runs no action: any sources will do)
    print(f"{'sources':50} {'action':>9} {'bare':>9} {'ratio':>7}")
    for src in sources:
        act = per_operation(src, "action")
        name = str(Path(src).resolve()) if src is not None else "installed"
        print(f"{name:50} {act:9.0f} {bare:9.0f} {act / bare:7.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
