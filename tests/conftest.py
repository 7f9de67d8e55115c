from __future__ import annotations

import inspect

import pytest
from hypothesis import HealthCheck, settings

# Property tests check properties, not speed. Hypothesis's per-example deadline (200 ms of
# the wall clock) and its too_slow health check measure the machine: beside a CPU hog on
# each core, one example of test_normalize_angle_lands_in_half_open_range took 470 ms and
# the test failed as flaky (its rerun met the deadline).
settings.register_profile(
    "pyrobots_aio", deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile("pyrobots_aio")


@pytest.fixture(autouse=True)
def _no_leaks(request: pytest.FixtureRequest) -> None:
    """Every async test in this suite checks that no task outlives it."""
    if inspect.iscoroutinefunction(request.function):
        request.getfixturevalue("no_leaked_tasks")
