"""Run every example as a user would (``python examples/NAME.py``); fail if one fails."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent
TIME_LIMIT = 600
NEEDS = {
    "create3_walk.py": (
        "irobot_create_msgs",
        'the ROS 2 wheels and the Create 3\'s interfaces: pip install -e ".[sim,ros2-build]" '
        "&& pyrobots-aio ros2 interfaces build",
    ),
    "random_walk_ros2.py": ("rclpy", 'the ROS 2 wheels: pip install -e ".[sim,ros2]"'),
}
"""Examples that need an optional extra: the module they import, and what to install."""


def main() -> int:
    failed = []
    for script in sorted(HERE.glob("*.py")):
        if script.name == Path(__file__).name:
            continue
        module, install = NEEDS.get(script.name, ("", ""))
        if module and importlib.util.find_spec(module) is None:
            print(f"{script.name:28} {'skipped':18}   needs {module}, not installed: {install}")
            continue
        start = time.monotonic()
        done = subprocess.run(
            [sys.executable, str(script)], timeout=TIME_LIMIT, check=False, capture_output=True
        )
        took = time.monotonic() - start
        status = "ok" if done.returncode == 0 else f"FAILED (exit {done.returncode})"
        print(f"{script.name:28} {status:18} {took:6.1f} s")
        if done.returncode != 0:
            failed.append(script.name)
            print(done.stdout.decode(errors="replace")[-3000:])
            print(done.stderr.decode(errors="replace")[-3000:])
    print(f"{len(failed)} failed: {failed}" if failed else "every example ran")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
