"""The plugin's fixtures and loop choice, registered when pytest-asyncio is recent enough.

pytest-asyncio runs an async fixture on the loop of its ``loop_scope``, fixed
when the fixture is defined; a robot must live on the loop of the test that
drives it. So ``robot``, ``sim_robot`` and ``no_leaked_tasks`` are plain
fixtures that pick, for each test, one of the async fixtures below defined for
every loop scope (``_robot_on_module_loop``, ...): the one of the test's loop.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
from typing import TYPE_CHECKING, Any, Literal

import pytest
import pytest_asyncio

from .. import ActionAbandonment, Robot
from ..loops import new_virtual_loop
from ._events import EventLog

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Mapping

Scope = Literal["function", "class", "module", "package", "session"]
_LOOP_SCOPES: tuple[Scope, ...] = ("function", "class", "module", "package", "session")
_SHARED: dict[
    str, Scope
] = {  # the fixtures of one robot for a whole module or session: name -> scope
    "module_robot": "module",
    "module_sim_robot": "module",
    "session_robot": "session",
    "session_sim_robot": "session",
}
_VIRTUAL_FIXTURES = frozenset({"sim_robot", "module_sim_robot", "session_sim_robot"})
_WHOSE = {
    "function": "its own",
    "class": "its class's",
    "module": "its module's",
    "package": "its package's",
    "session": "the session's",
}


# -- the loop --------------------------------------------------------------------


@pytest.hookimpl(tryfirst=True, optionalhook=True)
def pytest_asyncio_loop_factories(
    config: pytest.Config, item: pytest.Item
) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]] | None:
    """Run the tests that ask for virtual time on its loop; leave the others' loop alone.

    The hook is first-result: answering first (``tryfirst``) for those tests
    wins over a project's own factories; answering None for the others lets the
    project's hook, or else `DefaultLoop`, choose.
    """
    return {"virtual_time": new_virtual_loop} if _virtual_asked_by(item) else None


class DefaultLoop:
    """Answers last: asyncio's loop, through the current policy, when no other plugin chose.

    pytest-asyncio wants an answer for every test once any plugin implements
    the hook; ``asyncio.new_event_loop`` is what it would use without one (a
    uvloop policy, or the ``event_loop_policy`` fixture, still applies).
    """

    @pytest.hookimpl(trylast=True, optionalhook=True)
    def pytest_asyncio_loop_factories(
        self, config: pytest.Config, item: pytest.Item
    ) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]]:
        return {"asyncio": asyncio.new_event_loop}


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> None:
    """Fail a test set up so that a fixture or marker cannot work, saying what to change."""
    problem = _virtual_time_problem(item) or _shared_loop_problem(item)
    if problem is not None:
        pytest.fail(problem, pytrace=False)


def _virtual_asked_by(item: pytest.Item) -> str | None:
    """What asks for virtual time in ``item`` (the marker, or a fixture), or None."""
    if item.get_closest_marker("virtual_time"):
        return "marker 'virtual_time'"
    return _virtual_fixture_of(item)


def _virtual_fixture_of(item: pytest.Item) -> str | None:
    for name in getattr(item, "fixturenames", ()):
        if name in _VIRTUAL_FIXTURES:
            return f"fixture {name!r}"
    return None


def _virtual_time_problem(item: pytest.Item) -> str | None:
    """A test that asks for virtual time but that pytest-asyncio does not run.

    A fixture that needs virtual time would fail anyway; the marker is only
    held against a test it decorates itself (a module's ``pytestmark`` may
    cover its sync tests too).
    """
    if pytest_asyncio.is_async_test(item):
        return None
    asker = _virtual_fixture_of(item)
    if asker is None and any(mark.name == "virtual_time" for mark in item.own_markers):
        asker = "marker 'virtual_time'"
    if asker is None:
        return None
    if inspect.iscoroutinefunction(getattr(item, "obj", None)):
        return (
            f"{asker} runs the test on the virtual-time loop, but pytest-asyncio does not "
            "run this test: mark it @pytest.mark.asyncio"
        )
    return (
        f"{asker} needs an async test on the virtual-time loop: make it an async def test "
        "marked @pytest.mark.asyncio"
    )


def _shared_loop_problem(item: pytest.Item) -> str | None:
    """An async test using a module or session robot from a loop of another scope."""
    if not pytest_asyncio.is_async_test(item):
        return None
    own = _loop_scope_of(item)
    for name in getattr(item, "fixturenames", ()):
        scope = _SHARED.get(name)
        if scope is not None and scope != own:
            return (
                f"fixture {name!r} runs on the {scope}'s event loop, but this test runs on "
                f"{_WHOSE.get(own, own)}: mark it @pytest.mark.asyncio(loop_scope={scope!r})"
            )
    return None


def _loop_scope_of(item: pytest.Item) -> str:
    """The scope of the loop pytest-asyncio runs ``item`` on (its marker's, or the default)."""
    marker = item.get_closest_marker("asyncio")
    kwargs = {} if marker is None else marker.kwargs
    scope = kwargs.get("loop_scope") or kwargs.get("scope")
    return str(scope or item.config.getini("asyncio_default_test_loop_scope"))


# -- the checks ---------------------------------------------------------------------


async def _tasks_left(before: set[asyncio.Task[object]]) -> list[asyncio.Task[object]]:
    """The tasks not in ``before``, other than this one, still pending after one iteration."""
    await asyncio.sleep(0)  # let tasks that were just woken finish their last step
    current = asyncio.current_task()
    return [t for t in asyncio.all_tasks() - before if t is not current and not t.done()]


@contextlib.asynccontextmanager
async def _running_checked(
    robot: Robot, request: pytest.FixtureRequest, log: EventLog
) -> AsyncIterator[None]:
    """Run ``robot``; once shut down, fail on an abandoned action, a leftover task or lock."""
    before = asyncio.all_tasks()
    async with robot:
        yield
    if request.node.get_closest_marker("allow_leaks"):
        return
    abandoned = [
        f"{event.name}#{event.action} at {event.location}"
        for event in log.of_kind(ActionAbandonment)
    ]
    assert not abandoned, f"actions ignored cancellation and were abandoned: {abandoned}"
    held = robot.resources.held()
    assert not held, f"locks outlived the robot: {robot.resources!r}"
    left = await _tasks_left(before)
    assert not left, f"tasks outlived the robot: {left!r}"


def _new_robot(sim: bool, log: EventLog) -> Robot:
    if sim:
        from ..sim import SimRobot

        return SimRobot(instruments=[log])
    return Robot(dummy=True, instruments=[log])


# -- the fixtures, one per loop scope ---------------------------------------------------


def _robot_fixture(
    name: str, *, sim: bool, scope: Scope, loop_scope: Scope, log: str, doc: str = ""
) -> Any:
    """An async fixture running a robot (with the `EventLog` of fixture ``log``)."""

    async def running(request: pytest.FixtureRequest) -> AsyncIterator[Robot]:
        events = request.getfixturevalue(log)
        robot = _new_robot(sim, events)
        async with _running_checked(robot, request, events):
            yield robot

    running.__doc__ = doc
    return pytest_asyncio.fixture(running, scope=scope, loop_scope=loop_scope, name=name)


def _leak_fixture(name: str, *, loop_scope: Scope) -> Any:
    """An async fixture failing the test if a task it started is still pending at its end."""

    async def no_leaks(request: pytest.FixtureRequest) -> AsyncIterator[None]:
        before = asyncio.all_tasks()
        yield
        if request.node.get_closest_marker("allow_leaks"):
            return
        left = await _tasks_left(before)
        assert not left, f"tasks outlived the test: {left!r}"

    return pytest_asyncio.fixture(no_leaks, loop_scope=loop_scope, name=name)


def _on_the_test_s_loop(name: str, doc: str) -> Any:
    """A fixture that is fixture ``_{name}_on_{scope}_loop`` for the test's loop scope."""

    def on_the_test_s_loop(request: pytest.FixtureRequest) -> Any:
        return request.getfixturevalue(f"_{name}_on_{_loop_scope_of(request.node)}_loop")

    on_the_test_s_loop.__doc__ = doc
    return pytest.fixture(on_the_test_s_loop, name=name)


robot = _on_the_test_s_loop(
    "robot", "A running dummy robot on the test's loop; checks that no task or lock outlives it."
)
sim_robot = _on_the_test_s_loop(
    "sim_robot",
    "A running simulated robot (docked, seed 0) in lockstep virtual time; the test runs on "
    "the virtual-time loop. Checks that no task or lock outlives it.",
)
no_leaked_tasks = _on_the_test_s_loop(
    "no_leaked_tasks", "Fail the test if an asyncio task it started is still pending when it ends."
)


def _per_loop_scope() -> dict[str, Any]:
    """The hidden async fixtures the three above pick from, one per loop scope."""
    fixtures: dict[str, Any] = {}
    for scope in _LOOP_SCOPES:
        for sim, name in ((False, "robot"), (True, "sim_robot")):
            hidden = f"_{name}_on_{scope}_loop"
            fixtures[hidden] = _robot_fixture(
                hidden, sim=sim, scope="function", loop_scope=scope, log="robot_events"
            )
        hidden = f"_no_leaked_tasks_on_{scope}_loop"
        fixtures[hidden] = _leak_fixture(hidden, loop_scope=scope)
    return fixtures


globals().update(_per_loop_scope())


@pytest.fixture
def robot_events() -> EventLog:
    """The `EventLog` attached to the ``robot`` or ``sim_robot`` fixture."""
    return EventLog()


@pytest.fixture(scope="module")
def module_robot_events() -> EventLog:
    """The `EventLog` attached to the ``module_robot`` or ``module_sim_robot`` fixture."""
    return EventLog()


@pytest.fixture(scope="session")
def session_robot_events() -> EventLog:
    """The `EventLog` attached to the ``session_robot`` or ``session_sim_robot`` fixture."""
    return EventLog()


_SHARED_DOC = (
    "One running {what} for the whole {scope}, on the {scope}'s loop: its tests are marked "
    "@pytest.mark.asyncio(loop_scope={scope!r}). Checks that no task or lock outlives it."
)
module_robot = _robot_fixture(
    "module_robot", sim=False, scope="module", loop_scope="module", log="module_robot_events",
    doc=_SHARED_DOC.format(what="dummy robot", scope="module"),
)  # fmt: skip
module_sim_robot = _robot_fixture(
    "module_sim_robot", sim=True, scope="module", loop_scope="module", log="module_robot_events",
    doc=_SHARED_DOC.format(what="simulated robot in virtual time", scope="module"),
)  # fmt: skip
session_robot = _robot_fixture(
    "session_robot", sim=False, scope="session", loop_scope="session", log="session_robot_events",
    doc=_SHARED_DOC.format(what="dummy robot", scope="session"),
)  # fmt: skip
session_sim_robot = _robot_fixture(
    "session_sim_robot", sim=True, scope="session", loop_scope="session",
    log="session_robot_events",
    doc=_SHARED_DOC.format(what="simulated robot in virtual time", scope="session"),
)  # fmt: skip
