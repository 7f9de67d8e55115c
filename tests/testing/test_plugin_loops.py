"""The plugin's loop choice: virtual time for the tests that ask, the project's own loop elsewhere.

Also: the fixtures on module and session loops, and the errors that name
what a test is missing (the asyncio marker, the virtual_time marker, the loop scope).
"""

from __future__ import annotations

import textwrap

import pytest

pytest_plugins = ["pytester"]

# hypothesis' plugin, imported (and assertion-rewritten) at the inner run's summary, trips a
# CPython 3.11.7 bug (AST constructor recursion depth mismatch) when the outer run has not
# imported hypothesis yet.
QUIET = ("-p", "no:logging", "-p", "no:hypothesispytest")
INI = "[pytest]\nasyncio_mode = strict\nasyncio_default_fixture_loop_scope = function\n"

OWN_LOOP = """
    import asyncio

    class OwnLoop(asyncio.SelectorEventLoop):
        '''The project's own loop (uvloop, in real life).'''
    """


def _run(pytester: pytest.Pytester, source: str, *args: str) -> pytest.RunResult:
    pytester.makeini(INI)
    pytester.makepyfile(textwrap.dedent(source))
    return pytester.runpytest(*QUIET, *args)


_LOOPS = """
    import asyncio
    import pytest
    from conftest import OwnLoop
    from pyrobots_aio.loops import is_virtual

    def loop_kind():
        loop = asyncio.get_running_loop()
        return "virtual" if is_virtual(loop) else type(loop).__name__

    @pytest.mark.asyncio
    async def test_plain():
        assert loop_kind() == "OwnLoop"

    @pytest.mark.asyncio
    async def test_dummy_robot(robot):
        assert loop_kind() == "OwnLoop"
        assert robot.is_running

    @pytest.mark.asyncio
    @pytest.mark.virtual_time
    async def test_marked():
        assert loop_kind() == "virtual"

    @pytest.mark.asyncio
    async def test_sim_robot(sim_robot):
        assert loop_kind() == "virtual"
        await sim_robot.sleep(1.0)

    @pytest.mark.asyncio(loop_scope="module")
    @pytest.mark.virtual_time
    async def test_marked_on_the_module_loop():
        assert loop_kind() == "virtual"
    """


def test_a_project_s_loop_factory_hook_stands_where_virtual_time_is_not_asked(
    pytester: pytest.Pytester,
) -> None:
    pytester.makeconftest(
        textwrap.dedent(OWN_LOOP)
        + textwrap.dedent(
            """
            def pytest_asyncio_loop_factories(config, item):
                return {"own": OwnLoop}
            """
        )
    )
    result = _run(pytester, _LOOPS)
    result.assert_outcomes(passed=5)


def test_a_project_s_loop_policy_stands_where_virtual_time_is_not_asked(
    pytester: pytest.Pytester,
) -> None:
    pytester.makeconftest(
        textwrap.dedent(OWN_LOOP)
        + textwrap.dedent(
            """
            class OwnPolicy(asyncio.DefaultEventLoopPolicy):
                def new_event_loop(self):
                    return OwnLoop()

            PREVIOUS = []

            def pytest_configure(config):
                PREVIOUS.append(asyncio.get_event_loop_policy())
                asyncio.set_event_loop_policy(OwnPolicy())

            def pytest_unconfigure(config):
                asyncio.set_event_loop_policy(PREVIOUS.pop())
            """
        )
    )
    result = _run(pytester, _LOOPS)
    result.assert_outcomes(passed=5)


def test_without_a_loop_factory_hook_the_tests_run_on_asyncio_s_loop(
    pytester: pytest.Pytester,
) -> None:
    result = _run(
        pytester,
        """
        import asyncio
        import pytest
        from pyrobots_aio.loops import is_virtual

        @pytest.mark.asyncio
        async def test_plain():
            assert not is_virtual()
            standard = asyncio.new_event_loop()
            standard.close()
            assert type(asyncio.get_running_loop()) is type(standard)

        @pytest.mark.asyncio
        @pytest.mark.virtual_time
        async def test_marked():
            assert is_virtual()
        """,
    )
    result.assert_outcomes(passed=2)


def test_the_function_scoped_fixtures_run_on_the_test_s_loop_whatever_its_scope(
    pytester: pytest.Pytester,
) -> None:
    pytester.makepyfile(
        conftest="""
        import pytest

        @pytest.fixture(autouse=True)
        def _leaks(request):
            request.getfixturevalue("no_leaked_tasks")
        """
    )
    result = _run(
        pytester,
        """
        import asyncio
        import pytest
        from pyrobots_aio import action
        from pyrobots_aio.loops import is_virtual

        @action
        async def count(robot, n):
            await robot.sleep(1.0)
            return n + 1

        LOOPS = {}

        @pytest.mark.asyncio(loop_scope="module")
        async def test_robot_on_the_module_loop(robot, robot_events):
            LOOPS["first"] = asyncio.get_running_loop()
            assert await count(robot, 1) == 2
            assert robot_events.outcomes("count") == ["succeeded"]

        @pytest.mark.asyncio(loop_scope="module")
        async def test_a_fresh_robot_on_the_same_loop(robot, robot_events):
            assert asyncio.get_running_loop() is LOOPS["first"]
            assert await count(robot, 2) == 3
            assert robot_events.outcomes("count") == ["succeeded"]

        @pytest.mark.asyncio(loop_scope="session")
        async def test_sim_robot_on_the_session_loop(sim_robot):
            assert is_virtual()
            await sim_robot.undock()
            assert not sim_robot.state.docked

        @pytest.mark.asyncio(loop_scope="module")
        async def test_a_leak_on_the_module_loop_is_seen():
            asyncio.get_running_loop().create_task(asyncio.sleep(10), name="stray")

        @pytest.mark.asyncio(loop_scope="class")
        class TestOnTheClassLoop:
            async def test_robot(self, robot):
                assert await count(robot, 3) == 4
        """,
    )
    result.assert_outcomes(passed=5, errors=1)
    result.stdout.fnmatch_lines(
        [
            "*ERROR at teardown of test_a_leak_on_the_module_loop_is_seen*",
            "*tasks outlived the test*",
        ]
    )


def test_module_and_session_robots_are_shared_by_the_tests_on_their_loop(
    pytester: pytest.Pytester,
) -> None:
    pytester.makepyfile(
        test_one="""
        import asyncio
        import pytest
        from pyrobots_aio import EventKind, action

        pytestmark = pytest.mark.asyncio(loop_scope="module")

        @action
        async def note(robot, text):
            robot.state.notes = [*robot.state.notes, text]

        SEEN = []

        async def test_first(module_robot, module_robot_events):
            SEEN.append(module_robot)
            module_robot.state.notes = []
            await note(module_robot, "first")

        async def test_second(module_robot, module_robot_events):
            assert module_robot is SEEN[0]
            await note(module_robot, "second")
            assert module_robot.state.notes == ["first", "second"]
            assert module_robot_events.outcomes("note") == ["succeeded", "succeeded"]

        async def test_session_sim_robot(session_sim_robot):
            # a module-scoped loop here: refused, see the error test
            pass
        """,
        test_two="""
        import pytest
        from pyrobots_aio.loops import is_virtual

        pytestmark = pytest.mark.asyncio(loop_scope="session")

        async def test_a(session_sim_robot, session_robot_events):
            assert is_virtual()
            await session_sim_robot.undock()
            assert session_robot_events.outcomes("undock") == ["succeeded"]

        async def test_b(session_sim_robot, session_robot_events):
            assert not session_sim_robot.state.docked  # the same robot, still undocked
            t = session_sim_robot.time()
            await session_sim_robot.sleep(2.0)
            assert session_sim_robot.time() - t == pytest.approx(2.0)
        """,
    )
    pytester.makeini(INI)
    result = pytester.runpytest(*QUIET)
    result.assert_outcomes(passed=4, errors=1)
    assert (
        "fixture 'session_sim_robot' runs on the session's event loop, but this test runs on "
        "its module's: mark it @pytest.mark.asyncio(loop_scope='session')"
    ) in result.stdout.lines


_MISSING_ASYNCIO = """
    import pytest
    from pyrobots_aio.sim import SimRobot

    @pytest.mark.virtual_time
    async def test_marked_without_asyncio():
        async with SimRobot() as robot:
            await robot.sleep(1)

    async def test_sim_robot_without_asyncio(sim_robot):
        pass

    def test_sync_sim_robot(sim_robot):
        pass

    @pytest.mark.virtual_time
    def test_sync_marked():
        pass

    @pytest.mark.asyncio
    async def test_asyncio_without_virtual_time():
        async with SimRobot() as robot:
            await robot.sleep(1)

    @pytest.mark.virtual_time
    class TestMarkedAsAClass:
        def test_sync(self):  # the class's marker covers it too: nothing to run, no error
            pass
    """


def test_the_errors_name_the_marker_that_is_missing(pytester: pytest.Pytester) -> None:
    result = _run(pytester, _MISSING_ASYNCIO)
    result.assert_outcomes(passed=1, failed=1, errors=4)
    async_fix = "pytest-asyncio does not run this test: mark it @pytest.mark.asyncio"
    sync_fix = "make it an async def test marked @pytest.mark.asyncio"
    lines = result.stdout.lines
    assert f"marker 'virtual_time' runs the test on the virtual-time loop, but {async_fix}" in lines
    assert f"fixture 'sim_robot' runs the test on the virtual-time loop, but {async_fix}" in lines
    assert f"fixture 'sim_robot' needs an async test on the virtual-time loop: {sync_fix}" in lines
    assert (
        f"marker 'virtual_time' needs an async test on the virtual-time loop: {sync_fix}" in lines
    )
    result.stdout.fnmatch_lines(
        [
            "*LockstepError: this simulated robot runs in lockstep virtual time (realtime=False), "
            "but the event loop is an ordinary one; start it with pyrobots_aio.sim.run(main) or "
            "the pytest marker @pytest.mark.virtual_time, or pass realtime=True"
        ]
    )
