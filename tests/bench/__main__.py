"""Run every benchmark module, print a table, write ``bench-results.json``.

``python -m tests.bench [NAME ...]`` (what ``nox -s bench`` runs); NAME picks
modules by their suffix (``actions``, ``resources`` ...). Figures are compared
with the goals of DESIGN.md §10 as ratios or bounds measured in this run.
"""

from __future__ import annotations

import importlib
import json
import platform
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

HERE = Path(__file__).parent
OUT = Path("bench-results.json")

# figure name -> (goal text, check) ; checks are informative, never a test failure
GOALS: dict[str, tuple[str, Callable[[float], bool]]] = {
    "throughput_ratio_vs_bare": ("<= 1.5x bare task, pure Python", lambda v: v <= 1.5),
    "throughput_actions_per_s": (">= 110,000/s (20x pyRobots)", lambda v: v >= 110_000),
    "cancel_to_handler_p99_us": ("p99 <= 500 us", lambda v: v <= 500),
    "rss_per_sleeping_action_kib": ("<= 4 KiB", lambda v: v <= 4),
    "cancel_all_10000_s": ("<= 0.2 s", lambda v: v <= 0.2),
    "python_work_inside_action_ratio": ("1.0x", lambda v: v <= 1.1),
    "handoff_p99_us": ("p99 <= 500 us", lambda v: v <= 500),
    "utilisation_pct_compound_contention": (">= 70 % (strict order: ~56 %)", lambda v: v >= 70),
    "max_wait_lowest_priority_s_aging": ("<= 60 s (strict priority: ~100 s)", lambda v: v <= 60),
    "running_1000_ms": ("<= 1 ms", lambda v: v <= 1),
    "write_to_callback_p99_us": ("p99 <= 500 us", lambda v: v <= 500),
    "pulses_seen_of_30": ("30 of 30", lambda v: v == 30),
    "idle_cpu_s_per_s_1000_monitors": ("~0", lambda v: v <= 0.005),
    "random_walk_realtime_factor": (">= 100x", lambda v: v >= 100),
    "random_walk_vs_limit": (">= 0.8 of the bare mj_step loop", lambda v: v >= 0.8),
    "random_walk_vs_limit_cpu": (">= 0.8 (thread CPU time)", lambda v: v >= 0.8),
    "recording_throughput_ratio": ("<= 2x", lambda v: v <= 2),
    "walk_recording_overhead_ratio": ("<= 1.5x no recording", lambda v: v <= 1.5),
    "replay_20k_resources_s": ("<= 2 s (was 16.5 s: quadratic)", lambda v: v <= 2),
    "replay_20k_overlapping_actions_s": ("<= 2 s (was 4.9 s: quadratic)", lambda v: v <= 2),
    "ros2_topic_to_callback_median_ratio": ("<= 1.2x plain rclpy, median", lambda v: v <= 1.2),
    "ros2_topic_to_callback_p99_ratio": ("<= 1.5x plain rclpy, p99", lambda v: v <= 1.5),
    "ros2_zero_loss_rate_ratio": (">= 0.8x plain rclpy's", lambda v: v >= 0.8),
    "ros2_publish_to_wire_p99_ratio": ("<= 1.5x plain rclpy, p99", lambda v: v <= 1.5),
    "ros2_drive_to_wire_p99_ratio": ("<= 1.5x plain rclpy, p99", lambda v: v <= 1.5),
    "watchdog_report_delay_max_ms": ("100 ms block reported <= 200 ms", lambda v: v <= 200),
    "watchdog_idle_cpu_overhead_pct": ("<= 1 % CPU", lambda v: v <= 1),
    "watchdog_busy_cpu_pct": ("<= 1 % CPU (counted directly)", lambda v: v <= 1),
    "watchdog_wakes_per_100_beats_busy": ("<= 25 (the loop carries the watch)", lambda v: v <= 25),
    "explore_fake_200_s": ("<= 20 s (200 x 60 s walks, FakeBase)", lambda v: v <= 20),
    "explore_sim_100_s": ("<= 60 s (100 x 60 s walks, SimRobot)", lambda v: v <= 60),
}


def _verdict(check: Callable[[float], bool], value: float) -> str:
    return "  ok" if check(value) else "  MISSED"


def main(argv: list[str]) -> int:
    names = sorted(p.stem for p in HERE.glob("bench_*.py"))
    if argv:
        names = [n for n in names if n.removeprefix("bench_") in argv]
    results: dict[str, dict[str, float]] = {}
    for name in names:
        print(f"running {name} ...", flush=True)
        module = importlib.import_module(f"tests.bench.{name}")
        results[name.removeprefix("bench_")] = module.run()
    print(f"\n{'figure':48} {'value':>14}  goal")
    for group, figures in results.items():
        print(f"[{group}]")
        for key, value in figures.items():
            entry = GOALS.get(key)
            goal, mark = ("", "") if entry is None else (entry[0], _verdict(entry[1], value))
            print(f"  {key:46} {value:14.3f}  {goal}{mark}")
    OUT.write_text(
        json.dumps(
            {"python": sys.version, "machine": platform.platform(), "results": results},
            indent=2,
        )
    )
    print(f"\nwrote {OUT.resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
