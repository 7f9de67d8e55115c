"""Reading a number from a caller: the one check behind every numeric parameter.

A parameter that takes a number (a speed, a pose coordinate, a number of
seconds, a firing rate) gets a float or a `ValueError` that names the
parameter, shows the value and says what was expected. Refused everywhere:

- NaN and the infinities (a NaN compares false with everything, so a monitor,
  a timer or a controller fed one never does what was meant);
- an int too large for a float (``10**400``), which ``float()`` would turn
  into an `OverflowError` deep inside the library;
- a bool (``True`` is an int to Python, but ``speed=True`` is a mistake);
- anything that is not a real number (a string, None, a complex).

Each caller words what it expects (``"a positive number of seconds"``) and may
raise a `ValueError` subclass of its own (`InvalidPoseError`,
`InvalidConditionError`).
"""

from __future__ import annotations

import math
from numbers import Real

_SHOWN_CHARS = 200
_LOG10_2 = math.log10(2)


def shown(value: object) -> str:
    """Return a one-line, bounded ``repr`` of ``value`` for error messages.

    An int too large for a float is shown by its size (its digits could run to
    thousands, and Python refuses to print more than 4300 of them).

    Examples:
        >>> shown(0.5), shown(-(10**400)), shown("x" * 300)[-6:]
        ('0.5', '-an int of about 10**400', 'xxx...')
    """
    if isinstance(value, int) and not isinstance(value, bool) and _too_large(value):
        sign = "-" if value < 0 else ""
        return f"{sign}an int of about 10**{round(value.bit_length() * _LOG10_2)}"
    try:
        text = repr(value)
    except ValueError:  # a container holding an int of more than 4300 digits
        return f"<{type(value).__name__} holding an int too large to print>"
    return text if len(text) <= _SHOWN_CHARS else text[: _SHOWN_CHARS - 3] + "..."


def _too_large(value: int) -> bool:
    try:
        float(value)
    except OverflowError:
        return True
    return False


def as_float(value: object) -> float | None:
    """Return ``value`` as a finite float, or None if it is not a finite real number.

    A bool is not a number here; an int too large for a float is not finite.

    Examples:
        >>> as_float(3), as_float(True), as_float(float("nan")), as_float(10**400)
        (3.0, None, None, None)
    """
    if type(value) is float:  # the common case, without the ABC check
        return value if math.isfinite(value) else None
    if isinstance(value, bool) or not isinstance(value, Real):
        return None
    try:
        number = float(value)
    except (OverflowError, ValueError):  # an int beyond float range; a Real that refuses float()
        return None
    return number if math.isfinite(number) else None


def finite(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    positive: bool = False,
    must: str | None = None,
    fix: str | None = None,
    error: type[ValueError] = ValueError,
) -> float:
    """Return ``value`` as a finite float, or raise ``error`` naming ``name`` and the value.

    Args:
        name: The parameter, as the caller wrote it (``"speed"``, ``"poll="``).
        value: What the caller passed.
        low: The least value allowed (included), if any.
        high: The greatest value allowed (included), if any.
        positive: Refuse 0 and below.
        must: What the message says the value must be (default: built from
            the bounds, e.g. ``"a finite number from 0 to 1"``).
        fix: Appended to the message after ``"; "`` (e.g. ``"write e.g. poll=0.5"``).
        error: The `ValueError` (sub)class to raise.

    Raises:
        ValueError: ``"{name} must be {must}, got {value}"``, with a hint for a
            bool or an int too large for a float.

    Examples:
        >>> finite("speed", 2, positive=True)
        2.0
        >>> finite("speed", True)
        Traceback (most recent call last):
        ...
        ValueError: speed must be a finite number, got True (a bool is not a number)
    """
    number = as_float(value)
    in_range = number is not None and (
        (low is None or number >= low)
        and (high is None or number <= high)
        and (not positive or number > 0)
    )
    if number is not None and in_range:
        return number
    expected = must if must is not None else _expected(low, high, positive=positive)
    message = f"{name} must be {expected}, got {shown(value)}{_hint(value)}"
    raise error(message if fix is None else f"{message}; {fix}")


def _expected(low: float | None, high: float | None, *, positive: bool) -> str:
    what = "a positive finite number" if positive else "a finite number"
    if low is not None and high is not None:
        return f"{what} from {low:g} to {high:g}"
    if low is not None:
        return f"{what} of at least {low:g}"
    if high is not None:
        return f"{what} of at most {high:g}"
    return what


def _hint(value: object) -> str:
    if isinstance(value, bool) or type(value).__name__ in {"bool", "bool_"}:  # numpy's too
        return " (a bool is not a number)"
    if isinstance(value, int) and _too_large(value):
        return " (too large for a float)"
    return ""
