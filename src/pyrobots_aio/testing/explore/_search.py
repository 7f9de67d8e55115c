"""The search: Hypothesis draws schedules, runs them, and shrinks the first that fails."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from hypothesis import HealthCheck, Phase, Verbosity, given, settings
from hypothesis import strategies as st

from ...motion import SENSORS
from ._schedule import (
    At,
    Bump,
    Cancel,
    Cliff,
    Disturbance,
    EmergencyStop,
    Hit,
    On,
    Pause,
    Preempt,
    Reading,
    Silence,
    StaleOdometry,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from hypothesis.strategies import SearchStrategy

    from ._scenario import Scenario

LONG_FACTOR = 10
"""The ``long`` profile's examples, per example asked for."""

_SECONDS = (0.5, 2.0, 10.0)


def _kinds(boundaries: Sequence[str]) -> dict[type[Disturbance], SearchStrategy[Disturbance]]:
    """Each shipped disturbance's values, simplest first (Hypothesis shrinks towards those)."""
    return {
        Bump: st.builds(Bump, st.sampled_from(Bump.SIDES), st.sampled_from((0.0, 0.5, 2.0))),
        Cliff: st.builds(Cliff, st.sampled_from(Cliff.POSITIONS), st.sampled_from((0.0, 0.5))),
        Reading: st.builds(
            Reading,
            st.sampled_from(Reading.POSITIONS),
            st.sampled_from((0.02, 0.1, 0.3)),
            st.sampled_from((0.0, 0.5)),
        ),
        Silence: st.builds(
            Silence, st.sampled_from([s.key for s in SENSORS]), st.sampled_from(_SECONDS)
        ),
        StaleOdometry: st.builds(StaleOdometry, st.sampled_from(_SECONDS)),
        Pause: st.builds(Pause, st.sampled_from((0.1, 1.0, 5.0))),
        Cancel: st.builds(Cancel, st.sampled_from((None, *boundaries))),
        EmergencyStop: st.builds(EmergencyStop, st.sampled_from((0.5, 2.0))),
        Preempt: st.builds(Preempt, st.sampled_from((0.1, 1.0))),
    }


def disturbances(
    drawn: Sequence[type[Disturbance] | Disturbance | SearchStrategy[Disturbance]],
    boundaries: Sequence[str],
) -> SearchStrategy[Disturbance]:
    """What to draw from: shipped classes (their values drawn), instances, or strategies.

    Raises:
        TypeError: A class this module cannot draw (give instances or a strategy).
    """
    kinds = _kinds(boundaries)
    choices: list[SearchStrategy[Disturbance]] = []
    for item in drawn:
        if isinstance(item, Disturbance):
            choices.append(st.just(item))
        elif isinstance(item, type):
            if item not in kinds:
                msg = (
                    f"explore cannot draw {item.__name__} values by itself; give instances "
                    f"({item.__name__}(...)) or a Hypothesis strategy of them"
                )
                raise TypeError(msg)
            choices.append(kinds[item])
        else:
            choices.append(item)
    return st.one_of(choices)


def schedules(scenario: Scenario[Any]) -> SearchStrategy[list[Hit]]:
    """Lists of up to ``max_hits`` hits, each at a boundary or a virtual time."""
    whens: list[SearchStrategy[On | At]] = []
    if scenario.boundaries:
        whens.append(
            st.builds(
                On,
                st.sampled_from(scenario.boundaries),
                st.integers(1, scenario.max_nth),
                st.sampled_from(("start", "end")),
            )
        )
    if scenario.horizon > 0:  # whole milliseconds, so the printed times read well
        ms = st.integers(0, round(scenario.horizon * 1000))
        whens.append(ms.map(lambda t: At(t / 1000)))
    what = disturbances(scenario.disturbances, scenario.boundaries)
    hit = st.builds(Hit, what, st.one_of(whens))
    return st.lists(hit, max_size=scenario.max_hits)


def _settings(examples: int, profile: str) -> settings:
    modes: dict[str, dict[str, Any]] = {
        "ci": {"derandomize": True, "database": None, "max_examples": examples},
        "dev": {"max_examples": examples},
        "long": {"max_examples": examples * LONG_FACTOR},
    }
    # Hypothesis's own default, not the profile loaded where this runs: with CI set in the
    # environment that is Hypothesis's "ci" profile (no example database, a reproduce blob
    # appended to every error), which would change what ``dev`` keeps and what a test sees
    return settings(
        settings.get_profile("default"),
        print_blob=False,
        deadline=None,  # a run takes what it takes on a loaded machine; virtual time is exact
        suppress_health_check=list(HealthCheck),
        phases=(Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink),
        report_multiple_bugs=False,
        verbosity=Verbosity.quiet,
        **modes[profile],
    )


class _Found(Exception):
    def __init__(self, schedule: list[Hit]) -> None:
        super().__init__(schedule)
        self.schedule = schedule


def search(
    scenario: Scenario[Any],
    fails: Callable[[list[Hit]], bool],
    examples: int,
    profile: str,
    salt: str = "",
) -> list[Hit] | None:
    """The smallest schedule for which ``fails`` is true, or None if no example failed.

    ``salt`` sets a search apart from others of the same scenario (another seed, in ``ci``).
    """

    def check(schedule: list[Hit]) -> None:
        if fails(schedule):
            raise _Found(schedule)

    # Hypothesis keys its seed (ci) and its saved examples (dev) on the test function's
    # source, which is this same function for every scenario: the scenario's key tells them apart
    check._hypothesis_internal_add_digest = (scenario.key + salt).encode()  # type: ignore[attr-defined]
    test = settings(_settings(examples, profile))(given(schedules(scenario))(check))
    try:
        test()
    except _Found as found:
        return found.schedule
    return None
