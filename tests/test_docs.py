"""The docstring examples of every module of the package run and hold (STYLE rule 20).

Each module with at least one example that is not marked ``# doctest: +SKIP``
is one test: its examples run as doctest runs them, with ``ELLIPSIS``.
"""

from __future__ import annotations

import doctest
import importlib
import io
import pkgutil
from pathlib import Path
from types import ModuleType

import pytest

import pyrobots_aio

_FINDER = doctest.DocTestFinder()


def _reraise(_name: str) -> None:
    """Re-raise a package's import error, which ``walk_packages`` would silently skip."""
    raise  # noqa: PLE0704  # called from inside the walk's except block


def _modules() -> list[str]:
    """Every module of the package, ``__main__`` modules left out (importing runs them)."""
    walked = pkgutil.walk_packages(
        pyrobots_aio.__path__, f"{pyrobots_aio.__name__}.", onerror=_reraise
    )
    names = [info.name for info in walked if info.name.rpartition(".")[2] != "__main__"]
    return sorted([pyrobots_aio.__name__, *names])


def _doctests(module: ModuleType) -> list[doctest.DocTest]:
    return [test for test in _FINDER.find(module, module.__name__) if test.examples]


def _runs_examples(name: str) -> bool:
    """Whether the module has an example that is not skipped."""
    tests = _doctests(importlib.import_module(name))
    return any(
        not example.options.get(doctest.SKIP, False) for test in tests for example in test.examples
    )


MODULES = _modules()
WITH_EXAMPLES = [name for name in MODULES if _runs_examples(name)]


def _packages(names: list[str]) -> set[str]:
    return {name.split(".")[1] for name in names if name.count(".") >= 2}


def test_every_subpackage_has_examples_that_run() -> None:
    assert _packages(WITH_EXAMPLES) == _packages(MODULES)
    assert {"_core", "actions", "events", "poses", "resources", "robot", "sim"} < _packages(MODULES)
    assert "pyrobots_aio.cli.__main__" not in MODULES
    # the modules whose examples were pinned before this test covered the whole package
    assert {
        "pyrobots_aio.poses._pose",
        "pyrobots_aio.poses._frames",
        "pyrobots_aio.poses._manager",
    } <= set(WITH_EXAMPLES)


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # an example that writes a file writes it there
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    report = io.StringIO()
    for test in _doctests(importlib.import_module(name)):
        runner.run(test, out=report.write)
    results = runner.summarize(verbose=False)
    assert report.getvalue() == ""
    assert results.failed == 0
    assert results.attempted > 0
