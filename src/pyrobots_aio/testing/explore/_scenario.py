"""Scenario: a behaviour, a base, the disturbances to draw and the invariants; explore, replay."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any, Generic

from ..._exceptions import InvariantViolation
from ...recording import load, render_timeline_html
from .._profiles import chosen_profile
from ._invariants import SAFETY, completes
from ._run import R, Run, Runner
from ._schedule import Bump, Hit
from ._search import search
from ._workers import search_in_processes

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable, Sequence

    from hypothesis.strategies import SearchStrategy

    from ._invariants import Invariant
    from ._schedule import Disturbance

_PUBLIC = "pyrobots_aio.testing.explore"


class Scenario(Generic[R]):
    """A behaviour on a base, the disturbances that may hit it, and what must hold.

    Args:
        behaviour: ``async def behaviour(robot)``, run on a fresh running base.
        base: Makes the base (``FakeBase``, ``lambda: SimRobot(seed=1)``).
        disturbances: What to draw: shipped `Disturbance` classes (their values
            drawn too), instances, or Hypothesis strategies of them.
        boundaries: The action names whose starts and ends hits are drawn at.
        invariants: `Invariant` objects, or functions of the `Run` that assert
            (default: `completes` and `SAFETY`).
        horizon: Hits are drawn at virtual times up to this many seconds
            after the start (0: at boundaries only).
        time_limit: Virtual seconds after which a run that has not ended fails.
        max_hits: The most hits in one schedule.
        max_nth: Hits at boundaries are drawn up to the ``max_nth`` action of a name.
        name: The variable the printed replay code calls the scenario.

    Example:
        >>> from pyrobots_aio.testing import FakeBase
        >>> from pyrobots_aio.testing.explore import On
        >>> async def out_and_back(robot: FakeBase) -> None:
        ...     await robot.undock()
        ...     await robot.dock()
        >>> scenario = Scenario(out_and_back, base=FakeBase, boundaries=["undock"])
        >>> run = scenario.replay([Hit(Bump(), On("undock", at="end"))])
        >>> run.violations, run.docked, [(round(t, 2), hit) for t, hit in run.hits]
        ([], True, [(2.36, Hit(Bump(), On('undock', at='end')))])
    """

    def __init__(
        self,
        behaviour: Callable[[R], Awaitable[object]],
        *,
        base: Callable[[], R],
        disturbances: Sequence[type[Disturbance] | Disturbance | SearchStrategy[Disturbance]] = (
            Bump,
        ),
        boundaries: Sequence[str] = (),
        invariants: Sequence[Invariant | Callable[[Run[R]], None]] = (completes(), *SAFETY),
        horizon: float = 60.0,
        time_limit: float = 600.0,
        max_hits: int = 3,
        max_nth: int = 3,
        name: str = "scenario",
    ) -> None:
        self.disturbances, self.boundaries = tuple(disturbances), tuple(boundaries)
        self.horizon, self.max_hits, self.max_nth, self.name = horizon, max_hits, max_nth, name
        self.runner = Runner(behaviour, base, invariants, time_limit)

    @property
    def key(self) -> str:
        """What tells this scenario's saved examples from another's."""
        what = getattr(self.runner.behaviour, "__qualname__", repr(self.runner.behaviour))
        return f"{self.name}:{what}:{self.disturbances!r}:{self.boundaries!r}"

    def run(self, schedule: Sequence[Hit] = (), *, record: str | Path | None = None) -> Run[R]:
        """Run the behaviour once under ``schedule``; ``record`` writes its recording there."""
        return self.runner.run(schedule, None if record is None else Path(record))

    def replay(self, schedule: Sequence[Hit]) -> Run[R]:
        """Run under ``schedule`` and check the invariants (the code a failure prints calls this).

        Raises:
            InvariantViolation: An invariant broke; the message has the schedule as code.
        """
        run = self.run(schedule)
        if run.violations:
            raise InvariantViolation(self.report(run), schedule, run.violations)
        return run

    def explore(
        self,
        *,
        examples: int = 100,
        profile: str | None = None,
        record_dir: str | Path | None = None,
        workers: int = 1,
    ) -> None:
        """Search for a schedule that breaks an invariant; fail with the smallest found.

        Args:
            examples: How many schedules to try (the ``long`` profile tries ten times more).
            profile: ``"ci"``, ``"dev"`` or ``"long"`` (see `pyrobots_aio.testing.explore`).
            record_dir: Where the failing run's recording and replay page go
                (default: a new temporary directory).
            workers: Processes to search in (forked; each takes its share of
                the examples with a seed of its own, and the first one's find wins).

        Raises:
            InvariantViolation: The shrunk schedule, printed as code that replays it,
                what broke, and the paths of the recording and its replay page.
        """
        chosen = chosen_profile(profile)
        if workers > 1:
            found = search_in_processes(self, self._fails, examples, chosen, workers)
        else:
            found = search(self, self._fails, examples, chosen)
        if found is None:
            return
        where = Path(record_dir or tempfile.mkdtemp(prefix="pyrobots_aio-explore-"))
        where.mkdir(parents=True, exist_ok=True)
        recording = where / f"{self.name}.jsonl"
        run = self.run(found, record=recording)
        page = recording.with_suffix(".html")
        page.write_text(render_timeline_html(load(recording)), encoding="utf-8")
        message = f"{self.report(run)}\nrecording: {recording}\nreplay page: {page}"
        raise InvariantViolation(message, found, run.violations, str(recording))

    def _fails(self, schedule: list[Hit]) -> bool:
        return bool(self.run(schedule).violations)

    def report(self, run: Run[Any]) -> str:
        """What broke in ``run``, and its schedule as code that replays it."""
        broken = "\n".join(f"  - {why}" for why in run.violations)
        hits = "".join(f"\n    {hit!r}," for hit in run.schedule)
        return (
            f"{self.name} broke its invariants under {len(run.schedule)} hit(s):\n{broken}\n"
            f"replay it in a test:\n\n{_imports(run.schedule)}\n"
            f"{self.name}.replay([{hits}\n])\n"
        )


def _imports(schedule: Sequence[Hit]) -> str:
    """The import lines the printed schedule needs."""
    modules: dict[str, set[str]] = {_PUBLIC: {"Hit"}}
    for hit in schedule:
        for value in (hit.what, hit.when):
            kind = type(value)
            module = _PUBLIC if kind.__module__.startswith(_PUBLIC) else kind.__module__
            modules.setdefault(module, set()).add(kind.__name__)
    return "\n".join(
        f"from {module} import {', '.join(sorted(names))}" for module, names in modules.items()
    )
