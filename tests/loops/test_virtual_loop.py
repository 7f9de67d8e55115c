from __future__ import annotations

import asyncio
import socket
import textwrap
import threading
from typing import TYPE_CHECKING

import anyio
import pytest

from pyrobots_aio import EventLoopError
from pyrobots_aio.loops import VirtualTimeLoop, is_virtual, new_virtual_loop, run_lockstep
from pyrobots_aio.loops._virtual import VirtualTimePolicy

if TYPE_CHECKING:
    from collections.abc import AsyncIterator

pytest_plugins = ["pytester"]


def _now() -> float:
    return asyncio.get_running_loop().time()


def test_a_new_loop_starts_at_zero() -> None:
    loop = new_virtual_loop()
    try:
        assert loop.time() == 0.0
        assert is_virtual(loop)
    finally:
        loop.close()


def test_sleeping_an_hour_takes_exactly_an_hour_of_virtual_time() -> None:
    async def main() -> list[float]:
        seen = [_now()]
        await asyncio.sleep(3600)
        seen.append(_now())
        await asyncio.sleep(3 * 86400)  # longer than asyncio's 24 h select cap
        seen.append(_now())
        return seen

    assert run_lockstep(main) == [0.0, 3600.0, 3600.0 + 3 * 86400]


def test_sleeps_and_timers_fire_in_real_time_order() -> None:
    async def main() -> list[tuple[str, float]]:
        log: list[tuple[str, float]] = []
        loop = asyncio.get_running_loop()

        async def sleeper(name: str, delay: float) -> None:
            await asyncio.sleep(delay)
            log.append((name, _now()))

        loop.call_later(1.5, lambda: log.append(("call_later", _now())))
        loop.call_at(0.25, lambda: log.append(("call_at", _now())))
        async with asyncio.TaskGroup() as tg:
            for name, delay in [("c", 3.0), ("a", 0.5), ("d", 7.0), ("b", 1.0)]:
                tg.create_task(sleeper(name, delay))
        return log

    assert run_lockstep(main) == [
        ("call_at", 0.25),
        ("a", 0.5),
        ("b", 1.0),
        ("call_later", 1.5),
        ("c", 3.0),
        ("d", 7.0),
    ]


def test_asyncio_timeout_fires_at_its_virtual_deadline() -> None:
    async def main() -> tuple[float, float]:
        with pytest.raises(TimeoutError):
            async with asyncio.timeout(2.5):
                await asyncio.sleep(10)
        after_timeout = _now()
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(asyncio.sleep(10), 0.75)
        return after_timeout, _now()

    assert run_lockstep(main) == (2.5, 3.25)


def test_wait_for_returns_when_the_awaitable_is_faster() -> None:
    async def main() -> tuple[str, float]:
        async def slow() -> str:
            await asyncio.sleep(4)
            return "done"

        return await asyncio.wait_for(slow(), 5), _now()

    assert run_lockstep(main) == ("done", 4.0)


def test_periodic_call_at_at_50_hz_ticks_500_times_in_10_seconds() -> None:
    async def main() -> tuple[list[float], float]:
        loop = asyncio.get_running_loop()
        ticks: list[float] = []
        finished = loop.create_future()

        def tick(n: int) -> None:
            ticks.append(loop.time())
            if n == 500:
                finished.set_result(None)
            else:
                loop.call_at((n + 1) / 50, tick, n + 1)

        loop.call_at(1 / 50, tick, 1)
        await finished
        return ticks, loop.time()

    ticks, end = run_lockstep(main)
    assert len(ticks) == 500
    assert ticks == [n / 50 for n in range(1, 501)]  # each tick lands on its own due time
    assert end == 10.0


def test_periodic_call_later_drifts_no_more_than_its_own_float_sums() -> None:
    async def main() -> tuple[int, float]:
        loop = asyncio.get_running_loop()
        count = 0
        finished = loop.create_future()

        def tick() -> None:
            nonlocal count
            count += 1
            if count == 500:
                finished.set_result(None)
            else:
                loop.call_later(0.02, tick)

        loop.call_later(0.02, tick)
        await finished
        return count, loop.time()

    count, end = run_lockstep(main)
    assert count == 500
    assert end == pytest.approx(10.0, abs=1e-9)


def test_sleeping_forever_is_never_woken_by_the_jump_to_the_next_timer() -> None:
    async def main() -> tuple[str, str, float]:
        async def forever() -> str:
            try:
                await anyio.sleep_forever()  # a timer at infinity
            except asyncio.CancelledError:
                return f"cancelled at {_now()}"
            return f"woken up at {_now()}"

        loop = asyncio.get_running_loop()
        task = loop.create_task(forever())
        await asyncio.sleep(5)
        answer: asyncio.Future[str] = loop.create_future()
        # Until the thread answers, the only timer is at infinity: the loop must block for real.
        waker = threading.Timer(0.05, loop.call_soon_threadsafe, (answer.set_result, "hi"))
        waker.start()
        try:
            got = await answer
        finally:
            waker.join()
        task.cancel()
        return got, await task, _now()

    assert run_lockstep(main) == ("hi", "cancelled at 5.0", 5.0)


def test_to_thread_completes_when_no_timer_is_pending() -> None:
    async def main() -> tuple[int, float]:
        return await asyncio.to_thread(sum, range(100_000)), _now()

    assert run_lockstep(main) == (4999950000, 0.0)


def test_thread_work_takes_no_virtual_time_while_timers_are_pending() -> None:
    async def main() -> tuple[list[float], float, float]:
        loop = asyncio.get_running_loop()
        fired: list[float] = []
        for n in range(1, 6):
            loop.call_at(n * 0.02, lambda: fired.append(loop.time()))
        release = threading.Event()
        threading.Timer(0.05, release.set).start()  # the thread blocks for real, briefly
        await asyncio.to_thread(release.wait)
        during = list(fired)
        after_thread = loop.time()
        await asyncio.sleep(1)
        return during, after_thread, fired[-1]

    assert run_lockstep(main) == ([], 0.0, 0.1)


def test_call_soon_threadsafe_wakes_a_loop_with_nothing_scheduled() -> None:
    async def main() -> tuple[str, float]:
        loop = asyncio.get_running_loop()
        answer: asyncio.Future[str] = loop.create_future()
        thread = threading.Thread(target=loop.call_soon_threadsafe, args=(answer.set_result, "hi"))
        thread.start()
        try:
            return await answer, loop.time()
        finally:
            thread.join()

    assert run_lockstep(main) == ("hi", 0.0)


def test_socket_io_is_served_without_advancing_virtual_time() -> None:
    async def main() -> tuple[bytes, float]:
        left, right = socket.socketpair()
        reader, writer = await asyncio.open_connection(sock=left)
        loop = asyncio.get_running_loop()
        loop.call_later(5, lambda: None)
        try:
            await loop.sock_sendall(right, b"ping\n")
            line = await reader.readline()
        finally:
            writer.close()
            await writer.wait_closed()
            right.close()
        return line, loop.time()

    assert run_lockstep(main) == (b"ping\n", 0.0)


def test_skip_ahead_moves_time_on_only_when_nothing_would_run_before() -> None:
    async def main() -> list[tuple[bool, float]]:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, VirtualTimeLoop)
        seen = [(loop.skip_ahead(1.0), loop.time())]  # nothing to do before t = 1
        seen.append((loop.skip_ahead(0.5), loop.time()))  # never backwards
        handle = loop.call_soon(lambda: None)  # a callback is ready
        seen.append((loop.skip_ahead(2.0), loop.time()))
        handle.cancel()
        await asyncio.sleep(0)
        timer = loop.call_at(3.0, lambda: None)  # a timer falls due at 3
        seen.append((loop.skip_ahead(3.0), loop.time()))
        seen.append((loop.skip_ahead(2.5), loop.time()))  # before it: fine
        timer.cancel()
        await asyncio.sleep(0)
        release = threading.Event()
        job = loop.run_in_executor(None, release.wait)  # a thread job holds time
        seen.append((loop.skip_ahead(4.0), loop.time()))
        release.set()
        await job
        for bad in (float("inf"), float("nan"), "soon"):
            with pytest.raises(ValueError, match="when must be a finite number"):
                loop.skip_ahead(bad)  # type: ignore[arg-type]
        assert loop.time() == 2.5  # a refused time leaves the clock alone
        loop.stop()  # a stopping loop must turn (stop() takes effect after this iteration)
        seen.append((loop.skip_ahead(5.0), loop.time()))
        return seen

    loop = VirtualTimeLoop()
    try:
        seen = loop.run_until_complete(main())
    finally:
        loop.close()
    assert seen == [
        (True, 1.0),
        (True, 1.0),
        (False, 1.0),
        (False, 1.0),
        (True, 2.5),
        (False, 2.5),
        (False, 2.5),
    ]


def test_run_passes_arguments_and_returns_the_result() -> None:
    async def add(a: int, b: int) -> int:
        await asyncio.sleep(1)
        return a + b

    assert run_lockstep(add, 2, 3) == 5


def test_run_propagates_the_exception_of_main() -> None:
    async def fail(message: str) -> None:
        await asyncio.sleep(1)
        raise ValueError(message)

    with pytest.raises(ValueError, match=r"^broken at t=1$"):
        run_lockstep(fail, "broken at t=1")


def test_run_closes_the_loop_and_cleans_up_what_main_left_behind() -> None:
    finalized: list[str] = []
    left: dict[str, object] = {}

    async def ticks() -> AsyncIterator[int]:
        try:
            yield 1
            yield 2
        finally:
            finalized.append("agen")

    def which_thread() -> threading.Thread:
        return threading.current_thread()

    async def main() -> None:
        left["loop"] = asyncio.get_running_loop()
        left["task"] = asyncio.get_running_loop().create_task(asyncio.sleep(100))
        left["agen"] = gen = ticks()
        await anext(gen)
        left["worker"] = await asyncio.get_running_loop().run_in_executor(None, which_thread)

    run_lockstep(main)
    loop, task, worker = left["loop"], left["task"], left["worker"]
    assert isinstance(loop, VirtualTimeLoop)
    assert loop.is_closed()
    assert isinstance(task, asyncio.Task)
    assert task.cancelled()
    assert finalized == ["agen"]
    assert isinstance(worker, threading.Thread)
    assert not worker.is_alive()


def test_run_refuses_to_nest_in_a_running_loop() -> None:
    async def inner() -> None:
        await asyncio.sleep(0)

    async def outer() -> None:
        run_lockstep(inner)

    with pytest.raises(EventLoopError) as caught:  # a RuntimeError too
        run_lockstep(outer)
    assert isinstance(caught.value, RuntimeError)
    assert str(caught.value) == (
        "pyrobots_aio.sim.run(inner) cannot run inside a running event loop: it runs inner on "
        "a virtual-time loop of its own; from async code, run it in a thread: "
        "await asyncio.to_thread(pyrobots_aio.sim.run, inner)"
    )


def test_run_in_a_thread_from_a_running_app_works_as_the_error_says() -> None:
    async def lockstep(hours: float) -> float:
        await asyncio.sleep(hours * 3600)
        return asyncio.get_running_loop().time()

    async def app() -> float:  # two simulated hours, in virtual time
        return await asyncio.to_thread(run_lockstep, lockstep, 2)

    assert asyncio.run(app()) == 7200.0


def test_anyio_sleep_and_fail_after_run_in_virtual_time() -> None:
    async def main() -> tuple[float, float, float]:
        await anyio.sleep(2)
        slept = anyio.current_time()
        with pytest.raises(TimeoutError):
            with anyio.fail_after(1.5):
                await anyio.sleep(60)
        failed = anyio.current_time()
        with anyio.move_on_after(0.25):
            await anyio.Event().wait()
        return slept, failed, anyio.current_time()

    assert run_lockstep(main) == (2.0, 3.5, 3.75)


def test_anyio_run_accepts_the_virtual_loop_factory() -> None:
    async def main() -> tuple[bool, float]:
        await anyio.sleep(42)
        return is_virtual(), anyio.current_time()

    assert anyio.run(main, backend_options={"loop_factory": new_virtual_loop}) == (True, 42.0)


def test_is_virtual_tells_loops_apart() -> None:
    plain = asyncio.new_event_loop()
    try:
        assert not is_virtual(plain)
    finally:
        plain.close()
    with pytest.raises(RuntimeError, match="no running event loop"):
        is_virtual()


def test_pending_timers_lists_live_timers_earliest_first() -> None:
    async def main() -> list[list[float]]:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, VirtualTimeLoop)
        seen = [[timer.when() for timer in loop.pending_timers()]]
        late = loop.call_later(5.0, lambda: None)
        loop.call_at(2.0, lambda: None)
        loop.call_later(1.0, lambda: None).cancel()  # cancelled: left out
        seen.append([timer.when() for timer in loop.pending_timers()])
        await asyncio.sleep(3.0)  # the timer due at 2.0 has fired
        seen.append([timer.when() for timer in loop.pending_timers()])
        late.cancel()
        seen.append([timer.when() for timer in loop.pending_timers()])
        return seen

    assert run_lockstep(main) == [[], [2.0, 5.0], [5.0], []]


def test_ready_callbacks_lists_what_runs_at_the_next_iteration() -> None:
    async def main() -> tuple[list[asyncio.Handle], list[list[asyncio.Handle]]]:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, VirtualTimeLoop)
        seen = [loop.ready_callbacks()]
        queued = [loop.call_soon(lambda: None), loop.call_soon(lambda: None)]
        loop.call_soon(lambda: None).cancel()  # cancelled: left out
        seen.append(loop.ready_callbacks())
        await asyncio.sleep(0)  # they have run
        seen.append(loop.ready_callbacks())
        return queued, seen

    queued, seen = run_lockstep(main)
    assert seen == [[], queued, []]


def test_the_policy_creates_virtual_loops() -> None:
    loop = VirtualTimePolicy().new_event_loop()
    try:
        assert isinstance(loop, VirtualTimeLoop)
    finally:
        loop.close()


def test_pytest_asyncio_runs_marked_tests_on_the_virtual_loop(pytester: pytest.Pytester) -> None:
    # The mechanism of pytest-asyncio >= 1.4: a pytest_asyncio_loop_factories hook
    # (conftest or plugin) returning {name: loop_factory} for each async test item.
    pytester.makeconftest(
        textwrap.dedent(
            """
            import asyncio
            from pyrobots_aio.loops import new_virtual_loop

            def pytest_configure(config):
                config.addinivalue_line("markers", "virtual_time: run on the virtual loop")

            def pytest_asyncio_loop_factories(config, item):
                if item.get_closest_marker("virtual_time"):
                    return {"virtual_time": new_virtual_loop}
                return {"asyncio": asyncio.new_event_loop}
            """
        )
    )
    pytester.makepyfile(
        test_virtual=textwrap.dedent(
            """
            import asyncio
            import pytest
            import pytest_asyncio
            from pyrobots_aio.loops import is_virtual

            pytestmark = pytest.mark.virtual_time

            @pytest_asyncio.fixture
            async def fixture_loop():
                await asyncio.sleep(5)
                yield asyncio.get_running_loop()

            @pytest.mark.asyncio
            async def test_sleep_advances_exactly():
                loop = asyncio.get_running_loop()
                start = loop.time()
                await asyncio.sleep(60)
                assert loop.time() - start == 60.0
                assert is_virtual(loop)

            @pytest.mark.asyncio
            async def test_async_fixtures_share_the_virtual_loop(fixture_loop):
                assert fixture_loop is asyncio.get_running_loop()
                assert fixture_loop.time() == 5.0
            """
        ),
        test_real=textwrap.dedent(
            """
            import asyncio
            import pytest
            from pyrobots_aio.loops import is_virtual

            @pytest.mark.asyncio
            async def test_unmarked_tests_keep_the_real_loop():
                assert not is_virtual()
            """
        ),
    )
    pytester.makeini(
        "[pytest]\nasyncio_mode = strict\nasyncio_default_fixture_loop_scope = function\n"
        "filterwarnings = error\n"
    )
    result = pytester.runpytest("-p", "no:pyrobots_aio", "-v")
    result.assert_outcomes(passed=3)
    result.stdout.fnmatch_lines(["*test_sleep_advances_exactly PASSED*"])
