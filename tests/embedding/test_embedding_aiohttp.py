"""The aiohttp example under ``web.run_app`` on 127.0.0.1, driven over HTTP, stopped by Ctrl-C."""

from __future__ import annotations

import asyncio
import itertools
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


@pytest.mark.asyncio
async def test_serves_and_on_ctrl_c_closes_its_websockets_then_stops_the_robot(
    serve: Callable[[list[str]], Server], aiohttp_command: list[str]
) -> None:
    server = serve(aiohttp_command)
    async with aiohttp.ClientSession(server.url, timeout=TIMEOUT) as client:
        first = await call(client, "POST", "/vacuum", rooms=1000)
        assert first == {"id": 1, "name": "vacuum", "state": "pending", "outcome": "not_done"}

        # a long-poll that gives up does not own the action: it goes on running
        polled = await call(client, "GET", "/actions/1", wait=0.2)
        assert (polled["state"], polled["outcome"]) == ("running", "not_done")

        # each change of the battery over a websocket, one percent a lap, none missed
        async with client.ws_connect("/battery") as socket:
            levels = [await socket.receive_json() for _ in range(4)]
        assert [round(a - b, 2) for a, b in itertools.pairwise(levels)] == [0.01] * 3

        # a long-poll in flight sees the cancellation; DELETE answers once it is done
        waiting = asyncio.create_task(call(client, "GET", "/actions/1", wait=60))
        cancelled = await call(client, "DELETE", "/actions/1")
        assert cancelled == {"id": 1, "name": "vacuum", "state": "done", "outcome": "cancelled"}
        assert await waiting == cancelled

        # many requests at once, each action awaited by a long-poll of its own
        started = await asyncio.gather(
            *(call(client, "POST", "/vacuum", rooms=2) for _ in range(40))
        )
        finished = await asyncio.gather(
            *(call(client, "GET", f"/actions/{a['id']}", wait=60) for a in started)
        )
        assert {(f["outcome"], f["result"]) for f in finished} == {("succeeded", 2)}

        # at Ctrl-C, a vacuum still runs and a websocket is open: the server closes the
        # socket (on_shutdown), then the robot cancels the vacuum
        await call(client, "POST", "/vacuum", rooms=1000)
        async with client.ws_connect("/battery") as socket:
            assert isinstance(await socket.receive_json(), float)
            server.interrupt()
            async for message in socket:
                assert message.type is aiohttp.WSMsgType.TEXT  # levels, until the close
            assert socket.close_code == aiohttp.WSCloseCode.GOING_AWAY
    output = await asyncio.to_thread(server.wait_for_clean_exit)
    assert "Running on http://127.0.0.1:" in output
