"""The builds of the actions core under test: the pure-Python one always, the compiled one if built.

``PYROBOTS_AIO_BUILD=compiled`` (``nox -s compiled``, which tests the
installed wheel) makes a missing compiled build an error rather than a skip.
"""

from __future__ import annotations

import importlib
import os
from typing import Any

import pytest

from pyrobots_aio.actions._build import BUILD
from pyrobots_aio.actions._pause import PyStepped

EXPECTED_BUILD = "compiled" if os.environ.get("PYROBOTS_AIO_BUILD") == "compiled" else "python"


def trampolines() -> list[Any]:
    """The pause trampolines to test: Python's, and C's where this install has it."""
    try:
        c_stepped = importlib.import_module("pyrobots_aio.actions._stepped").Stepped
    except ImportError:
        if EXPECTED_BUILD == "compiled":
            raise
        missing = pytest.mark.skip(reason="no C build here (an editable install): nox -s compiled")
        return [pytest.param(PyStepped, id="Python"), pytest.param(None, id="C", marks=missing)]
    return [pytest.param(PyStepped, id="Python"), pytest.param(c_stepped, id="C")]


__all__ = ["BUILD", "EXPECTED_BUILD", "trampolines"]
