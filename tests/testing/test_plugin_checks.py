"""The robot fixtures' leak checks fail when they should; without pytest-asyncio, a clear error."""

from __future__ import annotations

import importlib.metadata
import textwrap

import pytest

pytest_plugins = ["pytester"]

INI = "[pytest]\nasyncio_mode = strict\nasyncio_default_fixture_loop_scope = function\n"


def _run(pytester: pytest.Pytester, source: str, *args: str) -> pytest.RunResult:
    pytester.makeini(INI)
    pytester.makepyfile(textwrap.dedent(source))
    return pytester.runpytest(*args)


def test_an_abandoned_action_fails_the_test_that_used_the_robot(pytester: pytest.Pytester) -> None:
    result = _run(
        pytester,
        """
        import asyncio
        import pytest
        from pyrobots_aio import action

        @action
        async def deaf(robot):
            for _ in range(20):  # ignores cancellation (for 20 virtual seconds, then gives up)
                try:
                    await asyncio.sleep(1)
                except asyncio.CancelledError:
                    pass

        @pytest.mark.asyncio
        @pytest.mark.virtual_time
        async def test_deaf(robot):
            deaf(robot)
            await robot.sleep(0.1)

        @pytest.mark.asyncio
        @pytest.mark.virtual_time
        @pytest.mark.allow_leaks
        async def test_deaf_allowed(robot):
            deaf(robot)
            await robot.sleep(0.1)
        """,
        "-p",
        "no:logging",
    )
    result.assert_outcomes(passed=2, errors=1)
    result.stdout.fnmatch_lines(
        ["*actions ignored cancellation and were abandoned: [[]'deaf#1 at *test_*.py:*'[]]*"]
    )


def test_a_stray_task_fails_the_test_that_used_the_robot(pytester: pytest.Pytester) -> None:
    result = _run(
        pytester,
        """
        import asyncio
        import pytest

        @pytest.mark.asyncio
        async def test_stray(robot):
            asyncio.get_running_loop().create_task(asyncio.sleep(10), name="stray")

        @pytest.mark.asyncio
        async def test_clean(robot):
            await asyncio.create_task(asyncio.sleep(0))
        """,
    )
    result.assert_outcomes(passed=2, errors=1)
    result.stdout.fnmatch_lines(["*tasks outlived the robot: [[]<Task * name='stray'*"])


_SOURCE_NEEDING_THE_PLUGIN = """
    import pytest

    def test_uses_robot(robot):
        pass

    @pytest.mark.virtual_time
    def test_marked():
        pass

    def test_unrelated():
        assert 1 + 1 == 2
    """


@pytest.mark.parametrize(
    ("installed", "why"),
    [
        (None, "need pytest-asyncio; "),
        ("1.3.0", "need pytest-asyncio>=1.4, found 1.3.0; "),
    ],
)
def test_without_a_recent_pytest_asyncio_only_the_plugin_s_users_fail(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, installed: str | None, why: str
) -> None:
    real = importlib.metadata.version

    def version(name: str) -> str:
        if name != "pytest-asyncio":
            return real(name)
        if installed is None:
            raise importlib.metadata.PackageNotFoundError(name)
        return installed

    monkeypatch.setattr(importlib.metadata, "version", version)
    pytester.makepyfile(textwrap.dedent(_SOURCE_NEEDING_THE_PLUGIN))
    result = pytester.runpytest("-p", "no:asyncio")
    result.assert_outcomes(passed=1, errors=2)
    fix = 'pip install "pytest-asyncio>=1.4" (or pip install -e ".[testing]" in a checkout)'
    needs = f"the pyrobots_aio fixtures and virtual_time marker {why}{fix}"
    assert f"fixture 'robot': {needs}" in result.stdout.lines
    assert f"marker 'virtual_time': {needs}" in result.stdout.lines
