"""The FastAPI example under a real uvicorn on 127.0.0.1, driven over HTTP, stopped by Ctrl-C."""

from __future__ import annotations

import asyncio
import contextlib
import time
from typing import TYPE_CHECKING, Any

import httpx
import pytest

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable

    from conftest import Server

TIMEOUT = 60.0  # seconds for any one request: generous, the machine may be loaded


async def call(client: httpx.AsyncClient, method: str, path: str, **params: Any) -> Any:
    response = await client.request(method, path, params=params)
    assert response.status_code in {200, 202}, response.text
    return response.json()


async def levels(stream: httpx.Response) -> AsyncIterator[float]:
    """The battery levels of a Server-Sent Events stream."""
    async for line in stream.aiter_lines():
        if line:
            assert line.startswith("data: ")
            yield float(line.removeprefix("data: "))


def one_percent_steps(values: list[float]) -> bool:
    return values == [round(values[0] - 0.01 * i, 2) for i in range(len(values))]


@pytest.mark.asyncio
async def test_starts_polls_cancels_streams_and_stops_cleanly_on_ctrl_c(
    serve: Callable[[list[str]], Server], uvicorn_command: list[str]
) -> None:
    server = serve(uvicorn_command)
    async with httpx.AsyncClient(base_url=server.url, timeout=TIMEOUT) as client:
        # starting an action answers its id at once
        first = await call(client, "POST", "/patrol", laps=1000)
        assert first == {"id": 1, "name": "patrol", "state": "pending", "outcome": "not_done"}

        # a long-poll that gives up does not own the action: it goes on running
        polled = await call(client, "GET", "/actions/1", wait=0.2)
        assert (polled["state"], polled["outcome"]) == ("running", "not_done")

        # each change of the battery, streamed: one percent a lap, none missed
        async with client.stream("GET", "/battery", params={"count": 3}) as stream:
            assert stream.headers["content-type"].startswith("text/event-stream")
            streamed = [level async for level in levels(stream)]
        assert len(streamed) == 4  # the level, then three changes
        assert one_percent_steps(streamed), streamed
        async with (
            client.stream("GET", "/battery") as stream,
            contextlib.aclosing(levels(stream)) as battery,
        ):
            assert one_percent_steps([await anext(battery), await anext(battery)])
        # ... and leaves early: its stream ends on the server (else Ctrl-C would wait for it)

        # a long-poll in flight sees the cancellation; DELETE answers once it is done
        waiting = asyncio.create_task(call(client, "GET", "/actions/1", wait=TIMEOUT))
        cancelled = await call(client, "DELETE", "/actions/1")
        expected = {"state": "done", "outcome": "cancelled", "cancel_reason": "cancelled over HTTP"}
        assert cancelled == {"id": 1, "name": "patrol", **expected}
        assert await waiting == cancelled

        # an owning wait: the request's deadline cancels the action
        late = await client.post("/dock", params={"seconds": 3600, "deadline": 0.2})
        assert late.status_code == 504
        assert late.json()["detail"] == {
            "error": "not done within 0.2 s",
            "id": 2,
            "name": "dock",
            "state": "cancelling",
            "outcome": "not_done",
            "cancel_reason": "the task awaiting it was cancelled",
        }
        dock = await call(client, "GET", "/actions/2", wait=TIMEOUT)
        assert (dock["outcome"], dock["cancel_reason"]) == (
            "cancelled",
            "the task awaiting it was cancelled",
        )
        docked = await call(client, "POST", "/dock", seconds=0.05, deadline=TIMEOUT)
        assert docked == {
            "id": 3,
            "name": "dock",
            "state": "done",
            "outcome": "succeeded",
            "result": "docked",
        }

        # many requests at once, each action awaited by a long-poll of its own
        started = await asyncio.gather(
            *(call(client, "POST", "/patrol", laps=2) for _ in range(40))
        )
        finished = await asyncio.gather(
            *(call(client, "GET", f"/actions/{a['id']}", wait=TIMEOUT) for a in started)
        )
        assert {(f["outcome"], f["result"]) for f in finished} == {("succeeded", 2)}

        # a plain def endpoint, in a worker thread, hands its work to the robot's loop
        for _ in range(2):
            await call(client, "POST", "/patrol", laps=1000)
        assert await call(client, "POST", "/stop") == {"stopped": 2}
        stopped = [await call(client, "GET", f"/actions/{i}") for i in (44, 45)]
        assert {(s["outcome"], s["cancel_reason"]) for s in stopped} == {
            ("cancelled", "stop button")
        }

        # lockstep simulation in threads beside the service: deterministic, twice at once
        one, two = await asyncio.gather(
            *(call(client, "POST", "/simulate", distance=0.5) for _ in range(2))
        )
        assert one == two
        assert one["outcome"] == "succeeded"

        # left running: the robot cancels it when the server stops
        await call(client, "POST", "/patrol", laps=1000)
    server.interrupt()
    output = await asyncio.to_thread(server.wait_for_clean_exit)
    assert "Application shutdown complete." in output


@pytest.mark.asyncio
async def test_ctrl_c_waits_for_an_open_stream_and_the_robot_runs_until_it_closes(
    serve: Callable[[list[str]], Server], uvicorn_command: list[str]
) -> None:
    server = serve(uvicorn_command)
    waiting = "Waiting for connections to close"
    async with httpx.AsyncClient(base_url=server.url, timeout=TIMEOUT) as client:
        await call(client, "POST", "/patrol", laps=1000)
        async with (
            client.stream("GET", "/battery") as stream,
            contextlib.aclosing(levels(stream)) as battery,
        ):
            before = [await anext(battery)]
            server.interrupt()
            deadline = time.monotonic() + TIMEOUT
            while waiting not in server.output():  # uvicorn says it waits for this stream
                assert time.monotonic() < deadline, server.output()
                before.append(await anext(battery))
            after = [await anext(battery) for _ in range(3)]  # the robot still runs
            assert one_percent_steps(before + after)
    output = await asyncio.to_thread(server.wait_for_clean_exit)
    assert output.index(waiting) < output.index("robot stopped; tasks left: none")
