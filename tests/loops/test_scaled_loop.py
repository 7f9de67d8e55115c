"""The scaled-time loop: its factory's checks, and `run_scaled` (the pace itself: the doctest)."""

from __future__ import annotations

import asyncio
import math
import subprocess
import sys

import pytest

from pyrobots_aio.loops import ScaledTimeLoop, is_virtual, run_scaled, scaled_loop


@pytest.mark.parametrize("rate", [0, -1.0, math.inf, math.nan, True, "4"])
def test_a_rate_that_is_not_a_positive_number_is_refused(rate: object) -> None:
    with pytest.raises(ValueError, match="rate must be") as info:
        scaled_loop(rate)  # type: ignore[arg-type]
    assert str(info.value) == (
        f"rate must be a positive number (simulated seconds per second), got {rate!r}"
    )


def test_rate_one_is_an_ordinary_loop_and_any_other_a_scaled_one() -> None:
    plain, scaled = scaled_loop(1), scaled_loop(2.5)
    try:
        assert not isinstance(plain, ScaledTimeLoop)
        assert not is_virtual(plain)
        assert isinstance(scaled, ScaledTimeLoop)
        assert not is_virtual(scaled)
    finally:
        plain.close()
        scaled.close()


@pytest.mark.parametrize("rate", [1, 3])
def test_run_scaled_runs_main_with_its_arguments_on_the_loop_of_its_rate(rate: float) -> None:
    async def main(a: int, b: int) -> tuple[int, bool]:
        return a + b, isinstance(asyncio.get_running_loop(), ScaledTimeLoop)

    assert run_scaled(main, 2, 3, rate=rate) == (5, rate != 1)


CLOSE_UNDER_A_SIGNAL = """
import asyncio, signal, sys
from pyrobots_aio.loops import scaled_loop
from pyrobots_aio.loops._closing import SignalSafeLoop

kinds = {"stock": asyncio.SelectorEventLoop, "safe": SignalSafeLoop}
kinds["scaled"] = lambda: scaled_loop(1)
loop = kinds[sys.argv[1]]()
loop.add_signal_handler(signal.SIGUSR1, lambda: None)
close_pipe = loop._close_self_pipe

def close_then_signal():  # the window: the self-pipe is closed, the handlers not yet removed
    close_pipe()
    signal.raise_signal(signal.SIGUSR1)

loop._close_self_pipe = close_then_signal
loop.close()
print("closed")
"""


@pytest.mark.parametrize("kind", ["stock", "safe", "scaled"])
def test_a_signal_while_the_loop_closes_writes_to_no_closed_file(kind: str) -> None:
    done = subprocess.run(
        [sys.executable, "-c", CLOSE_UNDER_A_SIGNAL, kind],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert (done.returncode, done.stdout) == (0, "closed\n"), done.stderr
    if kind == "stock":  # asyncio's own order: the signal is written to the closed pipe
        assert "Bad file descriptor" in done.stderr
    else:
        assert done.stderr == ""
