"""Instructions per awaited action and per bare task, counted by callgrind (load-independent).

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
    # numpy's OpenBLAS threads spin while they wait: their count follows the wall clock
    threads = dict.fromkeys(("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"), "1")
    env = {**os.environ, "PYTHONHASHSEED": "0", **threads}
    if src is not None:
        env["PYTHONPATH"] = src
    command = [sys.executable, "-m", "tests.bench.instructions", "--run", kind, str(count)]
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
    return int(found[-1])  # the Python that ran the workload (the last to end)


def per_operation(src: str | None, kind: str) -> float:
    """Instructions one operation of ``kind`` costs with the sources ``src`` (None: installed)."""
    return (_instructions(src, kind, LONG) - _instructions(src, kind, SHORT)) / (LONG - SHORT)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description="Instructions per awaited action and bare task.")
    parser.add_argument("--src", action="append", help="a src/ directory to measure (repeatable)")
    parser.add_argument("--run", nargs=2, metavar=("KIND", "COUNT"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.run is not None:  # one run, under callgrind
        asyncio.run(_workload(args.run[0], int(args.run[1])))
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed; apt-get install valgrind", file=sys.stderr)
        return 1
    sources: list[str | None] = args.src or [None]
    bare = per_operation(sources[0], "bare")  # (it runs no action: any sources will do)
    print(f"{'sources':50} {'action':>9} {'bare':>9} {'ratio':>7}")
    for src in sources:
        act = per_operation(src, "action")
        name = str(Path(src).resolve()) if src is not None else "installed"
        print(f"{name:50} {act:9.0f} {bare:9.0f} {act / bare:7.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
