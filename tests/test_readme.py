from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parent.parent
README = (ROOT / "README.md").read_text()


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.DOTALL)


def test_readme_opens_with_the_two_commands() -> None:
    first, second = blocks("bash")[:2]
    assert README.index(first) < README.index("## ")
    assert "pip install" in first
    assert second.strip() == "python -m pip install nox uv && nox"


def test_ci_runs_the_readme_check_command() -> None:
    ci = (ROOT / ".ci" / "run").read_text()
    assert blocks("bash")[1].strip() in ci.splitlines()


def test_every_python_snippet_runs(tmp_path: Path) -> None:
    snippets = blocks("python")
    assert snippets
    for number, code in enumerate(snippets):
        script = tmp_path / f"test_snippet_{number}.py"
        script.write_text(code)
        runner = ["-m", "pytest", "-q", "-p", "no:cacheprovider"] if "def test_" in code else []
        done = subprocess.run(
            [sys.executable, *runner, str(script)],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
            cwd=tmp_path,
        )
        assert done.returncode == 0, done.stdout + done.stderr
