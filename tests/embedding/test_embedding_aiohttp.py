"""The aiohttp example under ``web.run_app`` on 127.0.0.1, driven over HTTP, stopped by Ctrl-C."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

import aiohttp
import pytest

if TYPE_CHECKING:
    from collections.abc import Callable

    from conftest import Server

TIMEOUT = aiohttp.ClientTimeout(total=60)  # generous: the machine may be loaded


async def call(client: aiohttp.ClientSession, method: str, path: str, **params: Any) -> Any:
    async with client.request(method, path, params=params) as response:
        assert response.status in {200, 202}, await response.text()
        return await response.json()


def one_percent_steps(values: list[float]) -> bool:
    return values == [round(values[0] - 0.01 * i, 2) for i in range(len(values))]


@pytest.mark.asyncio
async def test_starts_polls_cancels_streams_and_stops_cleanly_on_ctrl_c(
    serve: Callable[[str], Server],
) -> None:
    server = serve("embedded_aiohttp")
    async with aiohttp.ClientSession(server.url, timeout=TIMEOUT) as client:
        first = await call(client, "POST", "/patrol", laps=1000)
        assert first == {"id": 1, "name": "patrol", "state": "pending", "outcome": "not_done"}

        # a long-poll that gives up does not own the action: it goes on running
        polled = await call(client, "GET", "/actions/1", wait=0.2)
        assert (polled["state"], polled["outcome"]) == ("running", "not_done")

        # each change of the battery over a websocket, one percent a lap, none missed
        async with client.ws_connect("/battery") as socket:
            assert one_percent_steps([await socket.receive_json() for _ in range(4)])

        # a long-poll in flight sees the cancellation; DELETE answers once it is done
        waiting = asyncio.create_task(call(client, "GET", "/actions/1", wait=60))
        cancelled = await call(client, "DELETE", "/actions/1")
        assert cancelled == {"id": 1, "name": "patrol", "state": "done", "outcome": "cancelled"}
        assert await waiting == cancelled

        # many requests at once, each action awaited by a long-poll of its own
        started = await asyncio.gather(
            *(call(client, "POST", "/patrol", laps=2) for _ in range(40))
        )
        finished = await asyncio.gather(
            *(call(client, "GET", f"/actions/{a['id']}", wait=60) for a in started)
        )
        assert {(f["outcome"], f["result"]) for f in finished} == {("succeeded", 2)}

        # at Ctrl-C, a patrol still runs and a websocket is open: the server closes the
        # socket (on_shutdown), then the robot cancels the patrol
        await call(client, "POST", "/patrol", laps=1000)
        async with client.ws_connect("/battery") as socket:
            assert isinstance(await socket.receive_json(), float)
            server.interrupt()
            async for message in socket:
                assert message.type is aiohttp.WSMsgType.TEXT  # levels, until the close
            assert socket.close_code == aiohttp.WSCloseCode.GOING_AWAY
    output = await asyncio.to_thread(server.wait_for_clean_exit)
    assert "Running on http://127.0.0.1:" in output
