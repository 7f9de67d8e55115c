from __future__ import annotations

import textwrap

import pytest

pytest_plugins = ["pytester"]


def test_leak_check_fails_a_test_that_leaves_a_task(pytester: pytest.Pytester) -> None:
    pytester.makeconftest(
        textwrap.dedent(
            """
            import pytest

            @pytest.fixture(autouse=True)
            def _leaks(no_leaked_tasks):
                yield
            """
        )
    )
    pytester.makepyfile(
        textwrap.dedent(
            """
            import asyncio
            import pytest

            @pytest.mark.asyncio
            async def test_leaky():
                asyncio.get_running_loop().create_task(asyncio.sleep(10))

            @pytest.mark.asyncio
            async def test_clean():
                await asyncio.create_task(asyncio.sleep(0))
            """
        )
    )
    pytester.makeini(
        "[pytest]\nasyncio_mode = strict\nasyncio_default_fixture_loop_scope = function\n"
    )
    result = pytester.runpytest()
    result.assert_outcomes(passed=2, errors=1)
    result.stdout.fnmatch_lines(["*tasks outlived the test*"])
