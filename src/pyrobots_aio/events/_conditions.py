"""Monitor conditions: the ``**cond`` keywords, their validation and their truth test.

A condition turns a value of the watched key into "holds" or "does not hold".
Level conditions (``value``, ``above``, ``below``, predicates) fire while it
holds; edge conditions (``becomes``, ``increase``, ``decrease``) fire on each
change into holding. ``increase``/``decrease`` compare with a reference that
ratchets, as in pyRobots: it is the value at the last firing (initially the
value when the monitor was created), and while the value moves the other way
the reference follows it. So ``decrease=0.1`` on a battery charged from 0.5 to
1.0 then drained fires at 0.9, 0.8, ... and not only below 0.4. A reading of
None or NaN never becomes the reference, and a step is judged as `math.isclose`
does (``1.0 - 0.9`` is a hair under 0.1 in binary floating point, yet it is a
step of 0.1).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from numbers import Real
from typing import TYPE_CHECKING, Any, TypedDict, cast

from .._core._numbers import finite
from .._exceptions import InvalidConditionError

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

KINDS = ("value", "becomes", "above", "below", "increase", "decrease")
EDGES = frozenset({"becomes", "increase", "decrease"})
_RELATIVE = frozenset({"increase", "decrease"})
_NUMERIC = frozenset({"above", "below", "increase", "decrease"})
_ALL = (*KINDS, "held_for")
_LISTED = "value=, becomes=, above=, below=, increase=, decrease="


class Conditions(TypedDict, total=False):
    """The condition keywords of `EventManager.whenever`, `on` and `wait` (give one).

    Attributes:
        value: Level: holds while the key equals this value.
        becomes: Edge: fires on each change of the key into this value.
        above: Level: holds while the key is greater than this number.
        below: Level: holds while the key is less than this number.
        increase: Edge: fires when the key rose by at least this much above
            its reference: the value at the last firing (initially, at the
            monitor's creation), or the lowest value since if it fell below
            that. None and NaN readings are ignored.
        decrease: Edge: fires when the key fell by at least this much below
            its reference: the value at the last firing (initially, at the
            monitor's creation), or the highest value since if it rose above
            that. ``decrease=0.1`` on a battery charged from 0.5 to 1.0 then
            drained fires at 0.9, 0.8, ...
        held_for: Seconds the condition must hold before it fires; combines
            with any one of the others, or with a predicate.

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot
        >>> async def main() -> list[float]:
        ...     fired = []
        ...     async with Robot() as robot:
        ...         robot.state.battery = 0.5
        ...         robot.whenever("battery", decrease=0.1).do(
        ...             lambda: fired.append(robot.state.battery)
        ...         )
        ...         for level in (0.75, 1.0, 0.95, 0.9, 0.85, 0.8):  # recharged, then drained
        ...             robot.state.battery = level
        ...             await robot.sleep(0)
        ...     return fired
        >>> asyncio.run(main())
        [0.9, 0.8]
    """

    value: object
    becomes: object
    above: float
    below: float
    increase: float
    decrease: float
    held_for: float


@dataclass(frozen=True, slots=True)
class Condition:
    """A validated condition.

    Attributes:
        kind: One of `KINDS`, or None for a predicate (its result is the condition).
        target: The value or threshold given with ``kind``.
        held_for: Seconds it must hold before firing (0: fire at once).
    """

    kind: str | None
    target: object = None
    held_for: float = 0.0

    @property
    def edge(self) -> bool:
        """Whether it fires on changes into holding rather than while holding."""
        return self.kind in EDGES

    @property
    def relative(self) -> bool:
        """Whether it compares with a ratcheting reference (``increase``, ``decrease``)."""
        return self.kind in _RELATIVE

    def describe(self) -> str:
        """The condition as keywords, e.g. ``below=0.3 held_for=2.0`` ('' for a bare predicate)."""
        parts = [] if self.kind is None else [f"{self.kind}={self.target!r}"]
        if self.held_for:
            parts.append(f"held_for={self.held_for!r}")
        return " ".join(parts)

    def test(self) -> Callable[[Any, Any], bool]:
        """The truth test ``holds(value, reference)`` of a key condition."""
        return _TESTS[self.kind or "value"](self.target)

    def ratchet(self) -> Callable[[Any, Any], Any] | None:
        """``follow(value, reference) -> reference`` for ``increase``/``decrease``, else None.

        The reference follows a value that moved the other way (down for
        ``increase``, up for ``decrease``), replaces a missing one, and ignores
        a None or NaN value.
        """
        return _RATCHETS.get(self.kind or "value")


# State values are untyped (Any): a test may meet anything a backend or user wrote.


def _equals(target: Any) -> Callable[[Any, Any], bool]:
    return lambda value, _ref: bool(value == target)


def _above(target: Any) -> Callable[[Any, Any], bool]:
    return lambda value, _ref: value is not None and bool(value > target)


def _below(target: Any) -> Callable[[Any, Any], bool]:
    return lambda value, _ref: value is not None and bool(value < target)


def _increase(target: Any) -> Callable[[Any, Any], bool]:
    return lambda value, ref: _known(value) and _known(ref) and _at_least(value - ref, target)


def _decrease(target: Any) -> Callable[[Any, Any], bool]:
    return lambda value, ref: _known(value) and _known(ref) and _at_least(ref - value, target)


def _at_least(step: Any, target: float) -> bool:
    """``step >= target``, forgiving binary rounding (``1.0 - 0.9 == 0.09999999999999998``)."""
    return bool(step >= target) or math.isclose(step, target)  # to 1e-9 of the step


def _known(value: Any) -> bool:
    """Whether a reading can serve as (or be compared with) a reference: not None, not NaN."""
    return value is not None and not (isinstance(value, Real) and math.isnan(value))


def _follow_down(value: Any, ref: Any) -> Any:
    return value if _known(value) and (not _known(ref) or value < ref) else ref


def _follow_up(value: Any, ref: Any) -> Any:
    return value if _known(value) and (not _known(ref) or value > ref) else ref


_TESTS: dict[str, Callable[[Any], Callable[[Any, Any], bool]]] = {
    "value": _equals,
    "becomes": _equals,
    "above": _above,
    "below": _below,
    "increase": _increase,
    "decrease": _decrease,
}
_RATCHETS: dict[str, Callable[[Any, Any], Any]] = {
    "increase": _follow_down,
    "decrease": _follow_up,
}


def parse(var: str | None, cond: Mapping[str, object]) -> Condition:
    """Validate the keywords given for a monitor on key ``var`` (None: a predicate).

    Raises:
        InvalidConditionError: Unknown keyword, none or two conditions, a wrong
            type or value, or a key condition given with a predicate.
    """
    for name in cond:
        if name not in _ALL:
            raise InvalidConditionError(_unknown(name))
    held_for = _held_for(cond["held_for"]) if "held_for" in cond else 0.0
    given = [name for name in KINDS if name in cond]
    if var is None:
        if given:
            raise InvalidConditionError(
                f"{given[0]}= does not apply to a predicate: the predicate is the condition "
                "(return True while it holds); only held_for= may be added"
            )
        return Condition(None, None, held_for)
    if not given:
        raise InvalidConditionError(
            f"monitor on {var!r} has no condition; give one of {_LISTED} "
            "(held_for= may be added to it)"
        )
    if len(given) > 1:
        shown = ", ".join(f"{name}={cond[name]!r}" for name in given)
        raise InvalidConditionError(
            f"monitor on {var!r} has {len(given)} conditions ({shown}); give only one "
            "(held_for= is the one that combines), or watch a predicate for a compound condition"
        )
    kind = given[0]
    target = _number(kind, cond[kind]) if kind in _NUMERIC else _equalable(var, kind, cond[kind])
    return Condition(kind, target, held_for)


def check_frequency(max_firing_freq: object) -> float:
    """Validate ``max_firing_freq``; return it as a float."""
    return finite(
        "max_firing_freq",
        max_firing_freq,
        low=0,
        must="a number of firings per second >= 0 (0: unlimited)",
        error=InvalidConditionError,
    )


def check_poll(poll: object, var: str | None) -> float | None:
    """Validate ``poll`` (predicates only); return it as a float or None."""
    if poll is None:
        return None
    if var is not None:
        raise InvalidConditionError(
            f"poll= applies to predicates; the key {var!r} is checked on every write: drop poll="
        )
    return finite(
        "poll=",
        poll,
        positive=True,
        must="a number of seconds > 0 or None",
        error=InvalidConditionError,
    )


def check_blocking(blocking: object) -> bool:
    """Validate ``blocking``."""
    if not isinstance(blocking, bool):
        raise InvalidConditionError(f"blocking must be True or False, got {blocking!r}")
    return blocking


def check_numeric_key(key: str, condition: Condition, current: object) -> None:
    """Refuse a numeric condition on a key that holds something other than a number or None.

    A bool is refused too (``False > 0.5`` compares, but a flag has no threshold),
    as bool targets are.
    """
    if condition.kind not in _NUMERIC or current is None:
        return
    if isinstance(current, bool):
        fix = f"watch a flag with value= or becomes=, e.g. becomes={not current!r}"
    elif isinstance(current, Real):
        return
    else:
        fix = "use value= or becomes=, or a predicate"
    raise InvalidConditionError(
        f"{condition.kind}= compares numbers, but state key {key!r} holds {current!r} "
        f"({type(current).__name__}); {fix}"
    )


def _number(kind: str, target: object) -> float:
    positive = kind in _RELATIVE
    finite(  # the target itself is kept: descriptions show `above=0` as written
        f"{kind}=",
        target,
        positive=positive,
        must="a positive number" if positive else "a finite number",
        fix=f"write e.g. {kind}={'0.5' if positive else '0.3'}",
        error=InvalidConditionError,
    )
    return cast("float", target)


def _equalable(var: str, kind: str, target: object) -> object:
    """Refuse a NaN target of ``value=``/``becomes=``: nothing ever equals it."""
    if isinstance(target, Real) and math.isnan(target):
        raise InvalidConditionError(
            f"{kind}={target!r} can never fire: NaN equals nothing, not even NaN; to react to "
            f"a NaN reading, watch a predicate: "
            f"robot.whenever(lambda robot: math.isnan(robot.state[{var!r}]))"
        )
    return target


def _held_for(seconds: object) -> float:
    return finite(
        "held_for=",
        seconds,
        low=0,
        must="a number of seconds >= 0",
        fix="write e.g. held_for=2.0",
        error=InvalidConditionError,
    )


def _unknown(name: str) -> str:
    closest = difflib.get_close_matches(name, _ALL, n=1)
    hint = f" (did you mean {closest[0]}=?)" if closest else ""
    return f"unknown condition {name!r}{hint}; conditions are {_LISTED} and held_for="
