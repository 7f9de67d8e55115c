from __future__ import annotations

import runpy
from pathlib import Path

import pytest

import snippets_support
from pyrobots_aio import InvariantViolation
from pyrobots_aio.testing.explore import At, Bump, Hit
from snippets_support import ROOT, run_snippet

README = snippets_support.README.read_text()


def blocks(language: str) -> list[str]:
    return snippets_support.blocks(snippets_support.README, language)


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
    for number, code in enumerate(snippets):
        done = run_snippet(code, tmp_path, blocks("toml")[0], f"snippet_{number}")
        assert done.returncode == 0, done.stdout + done.stderr


def test_it_fits_in_two_screens() -> None:
    assert len(README.splitlines()) <= 130


def test_the_exploration_fails_as_the_readme_shows(tmp_path: Path) -> None:
    (example,) = [code for code in blocks("python") if "Scenario(" in code]
    script = tmp_path / "readme_exploration.py"
    script.write_text(example)
    walk = runpy.run_path(str(script))["WALK"]
    with pytest.raises(InvariantViolation) as failed:
        walk.replay([Hit(Bump(hold=0.5), At(0.0))])
    assert str(failed.value).rstrip("\n") == blocks("text")[0].rstrip("\n")
