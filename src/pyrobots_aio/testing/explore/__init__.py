"""Explore: search the disturbances that break a behaviour, with Hypothesis.

A `Scenario` is a behaviour on a base (``FakeBase``, ``SimRobot``), the
disturbances that may hit it (`Bump`, `Cliff`, `Reading`, `Silence`,
`StaleOdometry`, `Pause`, `Cancel`, `EmergencyStop`, `Preempt`, or your own
`Disturbance`), the action boundaries (`On`) and virtual times (`At`) they may
hit at, and the invariants that must hold (`completes`, `ends_docked`,
`no_forward_into_bumper`, `still_while_stopped`, `no_action_outlives_robot`,
`no_resource_held_twice`, or a function of the `Run` that asserts).
``scenario.explore(examples=100)`` runs the behaviour under schedules that
Hypothesis draws, each in lockstep virtual time; the first that breaks an
invariant is shrunk to the fewest, simplest hits, recorded, and raised as an
`InvariantViolation` whose message prints the schedule as code:
``scenario.replay([Hit(Bump(), On('undock'))])`` replays it, exactly.

Profiles: ``ci`` (the default: derandomized, the same examples every run),
``dev`` (random; failures kept in Hypothesis's database and tried first next
time) and ``long`` (``dev`` with ten times the examples); choose with
``profile=``, pytest's ``--explore-profile``, or ``PYROBOTS_AIO_EXPLORE``.
The pytest plugin's ``explore`` fixture and ``@pytest.mark.explore(examples=N)``
marker run a scenario with those settings and record into the test's ``tmp_path``.

Needs Hypothesis: the ``explore`` extra (``pip install "pyrobots-aio[explore]"``).
"""

try:
    import hypothesis as _hypothesis
except ImportError as missing:
    from ..._exceptions import ExploreUnavailableError

    msg = (
        "pyrobots_aio.testing.explore needs Hypothesis: "
        'pip install "pyrobots-aio[explore]" (or pip install -e ".[explore]" in a checkout)'
    )
    raise ExploreUnavailableError(msg) from missing

from .._profiles import PROFILES as PROFILES
from ._invariants import SAFETY as SAFETY
from ._invariants import Invariant as Invariant
from ._invariants import completes as completes
from ._invariants import ends_docked as ends_docked
from ._invariants import no_action_outlives_robot as no_action_outlives_robot
from ._invariants import no_forward_into_bumper as no_forward_into_bumper
from ._invariants import no_resource_held_twice as no_resource_held_twice
from ._invariants import still_while_stopped as still_while_stopped
from ._run import Run as Run
from ._scenario import Scenario as Scenario
from ._schedule import At as At
from ._schedule import Bump as Bump
from ._schedule import Cancel as Cancel
from ._schedule import Cliff as Cliff
from ._schedule import Disturbance as Disturbance
from ._schedule import EmergencyStop as EmergencyStop
from ._schedule import Hit as Hit
from ._schedule import On as On
from ._schedule import Pause as Pause
from ._schedule import Preempt as Preempt
from ._schedule import Reading as Reading
from ._schedule import Silence as Silence
from ._schedule import StaleOdometry as StaleOdometry
from ._schedule import Target as Target

del _hypothesis

__all__ = [
    "PROFILES",
    "SAFETY",
    "At",
    "Bump",
    "Cancel",
    "Cliff",
    "Disturbance",
    "EmergencyStop",
    "Hit",
    "Invariant",
    "On",
    "Pause",
    "Preempt",
    "Reading",
    "Run",
    "Scenario",
    "Silence",
    "StaleOdometry",
    "Target",
    "completes",
    "ends_docked",
    "no_action_outlives_robot",
    "no_forward_into_bumper",
    "no_resource_held_twice",
    "still_while_stopped",
]
