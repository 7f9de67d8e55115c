"""The ``explore`` fixture: a scenario explored with the marker's examples and the run's profile.

Registered whether or not Hypothesis is installed: only a test that asks for
the fixture imports `pyrobots_aio.testing.explore`, and without Hypothesis it
errors with `ExploreUnavailableError`, which names the extra to install.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from .explore import Scenario

EXAMPLES = 100
"""Examples of a test without ``@pytest.mark.explore(examples=N)``."""


@pytest.fixture
def explore(request: pytest.FixtureRequest, tmp_path: Path) -> Callable[[Scenario[Any]], None]:
    """``explore(scenario)``: `Scenario.explore` with this test's examples, profile and tmp_path.

    Examples come from ``@pytest.mark.explore(examples=N)`` (default
    `EXAMPLES`), processes from its ``workers=N`` (default 1); the profile
    from ``--explore-profile``, else the ``PYROBOTS_AIO_EXPLORE`` environment
    variable, else ``ci``; a failing run's recording and replay page go to
    the test's ``tmp_path``.
    """
    from . import explore as _explore  # noqa: F401 (an error naming the extra, if missing)

    marker = request.node.get_closest_marker("explore")
    given = marker.kwargs if marker else {}
    examples, workers = int(given.get("examples", EXAMPLES)), int(given.get("workers", 1))
    profile: str | None = request.config.getoption("explore_profile")

    def run(scenario: Scenario[Any]) -> None:
        scenario.explore(examples=examples, profile=profile, record_dir=tmp_path, workers=workers)

    return run
