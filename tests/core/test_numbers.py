"""The one number check behind every numeric parameter (`_core._numbers.finite`)."""

from __future__ import annotations

import math
import re
from fractions import Fraction

import numpy as np
import pytest

from pyrobots_aio import InvalidPoseError
from pyrobots_aio._core._numbers import as_float, finite, shown


@pytest.mark.parametrize(
    ("value", "got"),
    [
        (math.nan, "nan"),
        (math.inf, "inf"),
        (-math.inf, "-inf"),
        (10**400, "an int of about 10**400 (too large for a float)"),
        (-(10**400), "-an int of about 10**400 (too large for a float)"),
        (10**5000, "an int of about 10**5000 (too large for a float)"),  # beyond str()'s limit
        (Fraction(10**400, 3), "Fraction(1" + "0" * 187 + "..."),
        (True, "True (a bool is not a number)"),
        (np.bool_(False), "np.False_ (a bool is not a number)"),
        ("1.5", "'1.5'"),
        (None, "None"),
        (1j, "1j"),
    ],
    ids=lambda value: shown(value)[:20],
)
def test_anything_but_a_finite_real_number_is_a_value_error_naming_it(
    value: object, got: str
) -> None:
    message = f"speed must be a finite number, got {got}"
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        finite("speed", value)
    assert as_float(value) is None


@pytest.mark.parametrize(
    ("value", "expected"),
    [(2, 2.0), (-0.5, -0.5), (np.float32(0.25), 0.25), (np.int64(3), 3.0), (Fraction(1, 4), 0.25)],
)
def test_real_numbers_come_back_as_floats(value: object, expected: float) -> None:
    number = finite("speed", value)
    assert number == expected
    assert type(number) is float


def test_bounds_are_checked_and_worded() -> None:
    assert finite("window", 5, low=1, high=10) == 5.0
    with pytest.raises(ValueError, match=r"^window must be a finite number from 1 to 10, got 11$"):
        finite("window", 11, low=1, high=10)
    with pytest.raises(ValueError, match=r"^rate must be a finite number of at least 0, got -1$"):
        finite("rate", -1, low=0)
    with pytest.raises(ValueError, match=r"^turn must be a finite number of at most 3, got 4$"):
        finite("turn", 4, high=3)
    with pytest.raises(ValueError, match=r"^speed must be a positive finite number, got 0$"):
        finite("speed", 0, positive=True)


def test_callers_word_the_message_and_pick_the_error() -> None:
    with pytest.raises(
        InvalidPoseError, match=r"^x must be a real, got 'a'; write e\.g\. x=1\.0$"
    ) as caught:
        finite("x", "a", must="a real", fix="write e.g. x=1.0", error=InvalidPoseError)
    assert isinstance(caught.value, ValueError)


def test_shown_values_are_bounded() -> None:
    assert shown(10**400) == "an int of about 10**400"
    assert len(shown("x" * 10_000)) == 200
    assert shown([1.5]) == "[1.5]"
