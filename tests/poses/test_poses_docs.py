"""The docstring examples of the poses modules run and hold."""

from __future__ import annotations

import doctest
import importlib

import pytest


@pytest.mark.parametrize("module", ["_frames", "_manager", "_math", "_parse", "_pose"])
def test_docstring_examples(module: str) -> None:
    mod = importlib.import_module(f"pyrobots_aio.poses.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS, raise_on_error=False)
    assert result.failed == 0
    if module in {"_frames", "_manager", "_pose"}:
        assert result.attempted > 0
