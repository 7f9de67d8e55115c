from __future__ import annotations

import inspect
import signal
from typing import TYPE_CHECKING

import pytest
from hypothesis import HealthCheck, settings

if TYPE_CHECKING:
    from collections.abc import Iterator

# Property tests check properties, not speed. Hypothesis's per-example deadline (200 ms of
# the wall clock) and its too_slow health check measure the machine: beside a CPU hog on
# each core, one example of test_normalize_angle_lands_in_half_open_range took 470 ms and
# the test failed as flaky (its rerun met the deadline).
settings.register_profile(
    "pyrobots_aio", deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile("pyrobots_aio")


@pytest.fixture(autouse=True, scope="session")
def _sigint_reaches_children() -> Iterator[None]:
    """The programs the tests start get Ctrl-C as from a terminal, with Python's default handler.

    A test run started as a background job of a shell without job control (``pytest &``
    in a script) ignores SIGINT, and its children inherit that; the robot and
    ``stop_on_signals`` then rightly leave SIGINT alone, and each test that sends one
    waited for its hang guard (test_a_script_that_handles_the_cancellation_ends_normally
    failed so). A handler of this process is reset to the default in a child at its exec.
    """
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.fixture(autouse=True)
def _no_leaks(request: pytest.FixtureRequest) -> None:
    """Every async test in this suite checks that no task outlives it."""
    if inspect.iscoroutinefunction(request.function):
        request.getfixturevalue("no_leaked_tasks")
