"""The code blocks of the Markdown documents (README, guides), and running one as a user would.

A block's fence says what it is: ```` ```python ```` runs as it stands; a word
after the language marks a block that runs elsewhere, or not at all, and
`RUN_ELSEWHERE` and `SHOWN_ONLY` say where and why (`blocks` leaves marked blocks out of a plain
language's list, as the README's ROS 2 snippets have always been left out).
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).parent.parent
README = ROOT / "README.md"
GUIDES = ROOT / "docs"

FENCE = re.compile(r"^```(?P<info>[^`\n]*)\n(?P<code>.*?)^```", re.MULTILINE | re.DOTALL)

# marker -> where a block so marked runs, and why not where plain blocks do
RUN_ELSEWHERE = {
    "ros2": "it drives a sim-node in another process: tests/ros2/test_readme_ros2.py runs it",
    "ros2-robot": "it walks a sim-node in another process: tests/ros2/test_readme_ros2.py runs it",
    "ros2-create3": "it walks a Create 3 sim-node: tests/ros2/test_readme_ros2.py runs it",
    "ros2-serve": "it serves an action beside a sim-node: tests/ros2/test_readme_ros2.py runs it",
}
# marker -> why a block so marked never runs
SHOWN_ONLY = {
    "pyrobots": "pyRobots code, shown for comparison: it needs pyRobots, not this library",
}
MARKERS = RUN_ELSEWHERE | SHOWN_ONLY
# language -> why its blocks are not programs
NOT_PROGRAMS = {
    "bash": "shell commands: CI runs the README's (.ci/run), tests/cli runs the demo and replay",
    "toml": "configuration: the snippets run in a project that has it (run_snippet's config)",
    "text": "output shown, not code",
}

# a user's project: the pytest config the docs give, and any warning fails the run
PYTEST = ["-m", "pytest", "-q", "-p", "no:cacheprovider", "-W", "error"]


@dataclass(frozen=True)
class Block:
    """One fenced code block: where it is, its language, its marker (or ``""``) and its code."""

    document: Path
    line: int
    language: str
    marker: str
    code: str

    @property
    def where(self) -> str:
        """``path:line`` of the fence, relative to the checkout."""
        return f"{self.document.relative_to(ROOT)}:{self.line}"


def all_blocks(document: Path) -> list[Block]:
    """Every fenced block of ``document``, in order."""
    text = document.read_text(encoding="utf-8")
    found = []
    for match in FENCE.finditer(text):
        language, _, marker = match["info"].strip().partition(" ")
        line = text.count("\n", 0, match.start()) + 1
        found.append(Block(document, line, language, marker.strip(), match["code"]))
    return found


def blocks(document: Path, language: str, marker: str = "") -> list[str]:
    """The code of ``document``'s blocks of ``language`` that carry ``marker`` (none: unmarked)."""
    return [b.code for b in all_blocks(document) if (b.language, b.marker) == (language, marker)]


def guides() -> list[Path]:
    """Every page of the docs site."""
    return sorted(GUIDES.rglob("*.md"))


def run_snippet(
    code: str, workdir: Path, config: str, name: str
) -> subprocess.CompletedProcess[str]:
    """Run ``code`` as a script (under pytest if it defines tests) in a project with ``config``."""
    (workdir / "pyproject.toml").write_text(config)
    script = workdir / f"test_{name}.py"
    script.write_text(code)
    runner = PYTEST if "def test_" in code else []
    return subprocess.run(
        [sys.executable, *runner, str(script)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        cwd=workdir,
    )
