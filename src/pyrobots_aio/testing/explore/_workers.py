"""Searching in several processes: each worker explores its share with a seed of its own.

Hypothesis searches in one process; with ``workers=N`` a scenario's examples
are split between N forked processes, each a search of its own (worker ``i``
salts the scenario's key with ``i``, so the ``ci`` profile stays
deterministic worker by worker), each shrinking what it finds. The answer is
that of the first worker, in worker order, that found a failing schedule:
the same at every run. Forked, so a scenario needs no pickling (its
behaviour may be a closure); only the schedule found comes back.
"""

from __future__ import annotations

import multiprocessing
from functools import partial
from typing import TYPE_CHECKING, Any

from ._search import search

if TYPE_CHECKING:
    from collections.abc import Callable
    from multiprocessing.connection import Connection

    from ._scenario import Scenario
    from ._schedule import Hit


def _shares(examples: int, workers: int) -> list[int]:
    """``examples`` split between ``workers``, the first ones taking the remainder."""
    share, extra = divmod(examples, workers)
    return [share + (i < extra) for i in range(workers)]


def _worker(find: Callable[[], list[Hit] | None], conn: Connection) -> None:
    try:
        conn.send((find(), None))
    except Exception as error:
        conn.send((None, error))
    finally:
        conn.close()


def search_in_processes(
    scenario: Scenario[Any],
    fails: Callable[[list[Hit]], bool],
    examples: int,
    profile: str,
    workers: int,
) -> list[Hit] | None:
    """`search` split between ``workers`` forked processes; the first worker's find wins."""
    fork = multiprocessing.get_context("fork")
    started = []
    for index, share in enumerate(_shares(examples, workers)):
        theirs, ours = fork.Pipe(duplex=False)
        process = fork.Process(
            target=_worker,
            args=(partial(search, scenario, fails, share, profile, f"#{index}"), ours),
            name=f"explore-{scenario.name}-{index}",
            daemon=True,
        )
        process.start()
        ours.close()
        started.append((process, theirs))
    try:
        answers = [conn.recv() for _, conn in started]
    finally:
        for process, conn in started:
            conn.close()
            process.terminate()  # only a worker still running: the parent was interrupted
            process.join()
    for found, error in answers:
        if error is not None:
            raise error
        if found is not None:
            return found  # type: ignore[no-any-return]
    return None
