"""The one entry point for checks: `nox` runs lint, typecheck, tests and examples."""

from __future__ import annotations

import nox

nox.options.default_venv_backend = "uv|venv"
nox.options.sessions = ["lint", "typecheck", "tests", "examples"]
nox.options.reuse_existing_virtualenvs = True

INSTALL = ".[sim,mcap,live,test]"


@nox.session
def lint(session: nox.Session) -> None:
    """Ruff: lint rules and formatting."""
    session.install("ruff>=0.6")
    session.run("ruff", "check", ".")
    session.run("ruff", "format", "--check", ".")


@nox.session
def typecheck(session: nox.Session) -> None:
    """mypy --strict over the library, then over the typing checks of its public API."""
    session.install("mypy>=1.10", "-e", INSTALL)
    session.run("mypy", "--strict", "src")
    session.run("mypy", "--strict", "tests/typing")


@nox.session
def tests(session: nox.Session) -> None:
    """The test suite (virtual time where time matters)."""
    session.install("-e", INSTALL)
    # The page test opens a real browser (chromium): skipped, with its reason, where there is
    # none; .ci/run installs it and sets PYROBOTS_BROWSER_REQUIRED, so under CI it runs.
    session.run("pytest", *session.posargs, env={"MUJOCO_GL": "egl"})


@nox.session
def examples(session: nox.Session) -> None:
    """Run every example script from the command line, as a user would."""
    session.install("-e", INSTALL)
    session.run("python", "examples/run_all.py")


@nox.session
def bench(session: nox.Session) -> None:
    """Benchmarks: print a table and write bench-results.json."""
    session.install("-e", INSTALL, "py_trees>=2.2")  # py_trees: the side-by-side comparison
    session.run("python", "-m", "tests.bench", *session.posargs)
