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


def test_the_pytest_config_it_gives_is_pytest_asyncio_s() -> None:
    (config,) = blocks("toml")
    assert config.startswith("[tool.pytest.ini_options]\n")
    assert 'asyncio_default_fixture_loop_scope = "function"' in config.splitlines()


def test_every_python_snippet_runs(tmp_path: Path) -> None:
    snippets = blocks("python")
    assert snippets
    # a user's project: the pytest config the README gives, and any warning fails the run
    (tmp_path / "pyproject.toml").write_text(blocks("toml")[0])
    pytest_run = ["-m", "pytest", "-q", "-p", "no:cacheprovider", "-W", "error"]
    for number, code in enumerate(snippets):
        script = tmp_path / f"test_snippet_{number}.py"
        script.write_text(code)
        runner = pytest_run if "def test_" in code else []
        done = subprocess.run(
            [sys.executable, *runner, str(script)],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
            cwd=tmp_path,
        )
        assert done.returncode == 0, done.stdout + done.stderr
