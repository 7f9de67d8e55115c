"""retry and its exponential backoff: attempts as child actions, cancellation never retried."""

from __future__ import annotations

import asyncio
import itertools
import logging
import math
import re

import pytest

from log_support import logged
from pyrobots_aio import (
    ActionCancelled,
    ActionInterrupted,
    EventKind,
    Outcome,
    Resource,
    Robot,
    action,
    exponential,
    lock,
    retry,
    timeout,
)
from pyrobots_aio.supervision import Backoff
from pyrobots_aio.testing import EventLog

ARM = Resource("arm")


class Flaky(Robot):
    """``lift`` fails ``failures`` times with a RuntimeError, each attempt taking 0.2 s."""

    def __init__(self, failures: int = 2) -> None:
        self.record = EventLog()
        super().__init__(instruments=[self.record])
        self.failures = failures
        self.tries = 0

    @retry(4, backoff=exponential(0.1, factor=2))
    @action
    async def lift(self, height: float) -> str:
        self.tries += 1
        await self.sleep(0.2)
        if self.tries <= self.failures:
            raise RuntimeError(f"arm controller timeout (attempt {self.tries})")
        return f"lifted to {height}"

    def spawned(self, name: str) -> list[tuple[float, int | None]]:
        """(time, parent) of each action called ``name``, as spawned."""
        return [
            (round(e.time, 9), e.data["parent"])  # type: ignore[misc]
            for e in self.record.of_kind(EventKind.ACTION_SPAWNED, name)
        ]


# -- backoff ------------------------------------------------------------------------------


def test_delays_grow_by_the_factor_up_to_the_cap() -> None:
    assert list(exponential(0.1, factor=3, max=2.0).delays(5)) == [
        0.1,
        pytest.approx(0.3),
        pytest.approx(0.9),
        2.0,
        2.0,
    ]
    assert list(exponential(0.0).delays(3)) == [0.0, 0.0, 0.0]
    assert list(Backoff().delays(2)) == [0.1, 0.2]


def test_a_huge_number_of_retries_stays_at_the_cap() -> None:
    delays = exponential(1.0, factor=10, max=60.0).delays(10_000)
    assert list(itertools.islice(delays, 9_998, None)) == [60.0, 60.0]


def test_jitter_shortens_each_delay_within_its_fraction_and_a_seed_repeats_it() -> None:
    backoff = exponential(1.0, factor=2, max=8.0, jitter=0.25, seed=42)
    first, again = list(backoff.delays(200)), list(backoff.delays(200))
    assert first == again  # seeded: every run draws the same
    plain = list(exponential(1.0, factor=2, max=8.0).delays(200))
    assert all(d * 0.75 <= j <= d for j, d in zip(first, plain, strict=True))
    assert len(set(first)) > 100  # drawn, not fixed
    fresh = exponential(1.0, jitter=1.0)
    assert list(fresh.delays(5)) != list(fresh.delays(5))  # unseeded: each run draws anew


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"base": -1.0}, "backoff base must be finite and at least 0.0, got -1.0"),
        ({"factor": 0.5}, "backoff factor must be finite and at least 1.0, got 0.5"),
        ({"base": 2.0, "max": 1.0}, "backoff max must be finite and at least 2.0, got 1.0"),
        ({"max": math.inf}, "backoff max must be finite and at least 0.1, got inf"),
        ({"base": math.nan}, "backoff base must be finite and at least 0.0, got nan"),
        ({"base": "1"}, "backoff base must be a number, got '1'"),
        ({"jitter": 1.5}, "backoff jitter must be a fraction from 0 to 1, got 1.5"),
        ({"seed": "x"}, "backoff seed must be an int or None, got 'x'"),
    ],
)
def test_bad_backoffs_are_refused(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        exponential(**kwargs)  # type: ignore[arg-type]


NOT_CANCELLATION = "; cancellation (ActionCancelled, a BaseException) is never retried"


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        ((0,), {}, "retry() attempts must be a positive int, got 0"),
        ((True,), {}, "retry() attempts must be a positive int, got True"),
        (
            (3,),
            {"backoff": 0.1},
            "retry() backoff must be a Backoff, e.g. exponential(0.1), got 0.1",
        ),
        ((3,), {"on": ()}, "retry() on= takes Exception subclasses, got ()" + NOT_CANCELLATION),
        (
            (3,),
            {"on": (asyncio.CancelledError,)},
            "retry() on= takes Exception subclasses, got (<class 'asyncio.exceptions."
            "CancelledError'>,)" + NOT_CANCELLATION,
        ),
        (
            (3,),
            {"on": BaseException},
            "retry() on= takes Exception subclasses, got <class 'BaseException'>"
            + NOT_CANCELLATION,
        ),
    ],
)
def test_bad_retries_are_refused(
    args: tuple[object, ...], kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        retry(*args, **kwargs)  # type: ignore[arg-type]


def test_it_decorates_actions_only() -> None:
    with pytest.raises(TypeError, match=r"^retry\(3, .*\) decorates an @action, a bound action"):
        retry(3)(print)  # type: ignore[call-overload]


# -- retrying -----------------------------------------------------------------------------


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_each_attempt_is_a_child_action_after_its_backoff(
    caplog: pytest.LogCaptureFixture,
) -> None:
    async with Flaky(failures=2) as robot:
        with caplog.at_level(logging.INFO, "pyrobots_aio.supervision"):
            handle = robot.lift(0.3)
            assert await handle == "lifted to 0.3"
        assert robot.time() == pytest.approx(0.9)  # 0.2 + 0.1 + 0.2 + 0.2 + 0.2
    # the retrying action and its three attempts, each a child of it
    assert robot.spawned("lift") == [(0.0, None), (0.0, 1), (0.3, 1), (0.7, 1)]
    assert robot.record.outcomes("lift") == ["failed", "failed", "succeeded", "succeeded"]
    assert [r.getMessage() for r in logged(caplog)] == [
        "lift: attempt 1 of 4 failed (RuntimeError('arm controller timeout (attempt 1)')); "
        "retrying in 0.1 s",
        "lift: attempt 2 of 4 failed (RuntimeError('arm controller timeout (attempt 2)')); "
        "retrying in 0.2 s",
    ]


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_last_attempts_error_is_the_actions() -> None:
    async with Flaky(failures=10) as robot:
        handle = robot.lift(0.3)
        with pytest.raises(RuntimeError, match=r"^arm controller timeout \(attempt 4\)$"):
            await handle
        assert handle.outcome is Outcome.FAILED
        assert robot.tries == 4
        assert robot.time() == pytest.approx(4 * 0.2 + 0.1 + 0.2 + 0.4)


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_error_not_named_by_on_is_not_retried() -> None:
    @retry(5, on=(ConnectionError,))
    @action
    async def connect(robot: Robot) -> None:
        robot.state.tries = robot.state.get("tries", 0) + 1
        raise ValueError("bad address")

    async with Robot() as robot:
        with pytest.raises(ValueError, match=r"^bad address$"):
            await connect(robot)
        assert robot.state.tries == 1


@pytest.mark.asyncio
@pytest.mark.virtual_time
@pytest.mark.parametrize("at", [0.1, 0.25])  # during the first attempt; during the first backoff
async def test_cancelling_it_is_never_retried(at: float) -> None:
    async with Flaky(failures=10) as robot:
        handle = robot.lift(0.3)
        await robot.sleep(at)
        handle.cancel("operator")
        assert await handle.wait_done() is Outcome.CANCELLED
        await robot.sleep(10)
        assert robot.tries == 1
        assert robot.record.outcomes("lift")[-1] == "cancelled"
        assert len(robot.record.outcomes("lift")) == 2


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_attempt_preempted_from_elsewhere_is_not_retried() -> None:
    tries = []

    @retry(5)
    @action
    @lock(ARM)
    async def wave(robot: Robot) -> None:
        tries.append(robot.time())
        await robot.sleep(3600)

    @action
    @lock(ARM, priority=10, preempt=True)
    async def reflex(robot: Robot) -> None:
        await robot.sleep(0.1)

    async with Robot() as robot:
        handle = wave(robot)
        await robot.sleep(1)
        await reflex(robot)
        with pytest.raises(ActionInterrupted, match=r"preempted by reflex#\d+") as stop:
            await handle
        assert stop.value.handle.name == "wave"
        assert handle.outcome is Outcome.FAILED
        await robot.sleep(10)
        assert tries == [0.0]


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_an_attempt_that_times_out_counts_as_a_timeout_error() -> None:
    cleanups = []

    @timeout(1)
    @action
    async def slow(robot: Robot) -> None:
        try:
            await robot.sleep(3600)
        except ActionCancelled:
            cleanups.append(robot.time())
            raise

    async with Robot() as robot:
        with pytest.raises(ActionInterrupted, match=r"timeout after 1 s$"):
            await retry(3, backoff=exponential(0.5))(slow)(robot)
        assert cleanups == [1.0, 2.5, 4.5]  # 1 s, 0.5 s, 1 s, 1 s, 1 s
        with pytest.raises(ActionInterrupted, match=r"timeout after 1 s$"):
            await retry(3, on=(RuntimeError,))(slow)(robot)
        assert cleanups[3:] == [5.5]  # not retried: on= does not name TimeoutError


@pytest.mark.asyncio
@pytest.mark.virtual_time
async def test_the_call_form_on_bound_and_plain_actions() -> None:
    async def ping(robot: Robot, answer: str) -> str:
        robot.state.pings = robot.state.get("pings", 0) + 1
        if robot.state.pings < 2:
            raise ConnectionError("no answer")
        return answer

    async with Flaky(failures=1) as robot:
        assert await retry(2)(ping)(robot, "pong") == "pong"
        robot.tries = 0
        assert await retry(1)(robot.lift)(0.5) == "lifted to 0.5"  # bound: two layers of retry
    assert robot.record.names_started()[:3] == ["ping", "ping", "ping"]
