"""Embedded in aiohttp: the robot lives in a ``cleanup_ctx``; handlers drive it.

The cleanup context enters ``async with Robot()`` before the server accepts a
request and leaves it after the last one (aiohttp runs it in the task that
Ctrl-C cancels: the robot still winds down every action, bounded by
``cancel_grace``); then it logs the tasks left: none.

    POST   /vacuum?rooms=N         start an action; answer its id at once (202)
    GET    /actions/{id}?wait=S    long-poll: wait up to S s; giving up leaves it running
    DELETE /actions/{id}           cancel an action; answer once its cleanup is over
    GET    /battery                a websocket: the level, then each change; the server
                                   closes it on shutdown (``on_shutdown``)

Run: ``python examples/embedded_aiohttp.py`` serves on a free loopback port,
calls each endpoint as a client would, and stops;
``python examples/embedded_aiohttp.py --port 8080`` serves until Ctrl-C.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import weakref
from typing import TYPE_CHECKING, Any

import aiohttp
from aiohttp import web

from pyrobots_aio import ActionHandle, Outcome, Robot, action
from pyrobots_aio.cli import install_console_handler

if TYPE_CHECKING:
    from collections.abc import AsyncIterator

log = logging.getLogger("embedded_aiohttp")

ROBOT = web.AppKey("robot", Robot)
ACTIONS = web.AppKey("actions", dict[int, ActionHandle[Any]])
SOCKETS = web.AppKey("sockets", weakref.WeakSet[web.WebSocketResponse])


@action
async def vacuum(robot: Robot, rooms: int) -> int:
    """Vacuum ``rooms`` rooms, 0.1 s each; each room costs one percent of the battery."""
    for room in range(rooms):
        robot.state.room = room
        await robot.sleep(0.1)
        robot.state.battery = round(robot.state.battery - 0.01, 2)
    return rooms


async def robot_context(app: web.Application) -> AsyncIterator[None]:
    before = asyncio.all_tasks()
    async with Robot() as robot:
        robot.state.update(battery=1.0, room=None)
        app[ROBOT] = robot
        app[ACTIONS] = {}
        log.info("robot started")
        yield
    left = sorted(task.get_name() for task in asyncio.all_tasks() - before)
    log.info("robot stopped; tasks left: %s", left or "none")


def answer(handle: ActionHandle[Any], status: int = 200) -> web.Response:
    body = {"id": handle.id, "name": handle.name, "state": handle.state.value}
    body["outcome"] = handle.outcome.value
    if handle.outcome is Outcome.SUCCEEDED:
        body["result"] = handle.result()
    return web.json_response(body, status=status)


def find(request: web.Request) -> ActionHandle[Any]:
    ident = request.match_info["ident"]
    handle = request.app[ACTIONS].get(int(ident))
    if handle is None:
        raise web.HTTPNotFound(text=f"no action #{ident}")
    return handle


async def start_vacuum(request: web.Request) -> web.Response:
    handle = vacuum(request.app[ROBOT], int(request.query.get("rooms", 3)))
    request.app[ACTIONS][handle.id] = handle
    return answer(handle, status=202)


async def poll_action(request: web.Request) -> web.Response:
    handle = find(request)
    with contextlib.suppress(TimeoutError):
        async with asyncio.timeout(float(request.query.get("wait", 0))):
            await handle.wait_done()  # not owning: giving up leaves the action running
    return answer(handle)


async def cancel_action(request: web.Request) -> web.Response:
    handle = find(request)
    handle.cancel("cancelled over HTTP")
    await handle.wait_done()  # its cleanup is bounded by the robot's cancel_grace
    return answer(handle)


async def send_levels(robot: Robot, socket: web.WebSocketResponse) -> None:
    changes = robot.watch("battery")  # subscribed before the level is read: none missed
    await socket.send_json(robot.state.battery)
    async for level in changes:  # ends when the robot stops
        await socket.send_json(level)


async def battery(request: web.Request) -> web.WebSocketResponse:
    socket = web.WebSocketResponse()
    await socket.prepare(request)
    request.app[SOCKETS].add(socket)
    sending = asyncio.create_task(send_levels(request.app[ROBOT], socket))
    try:
        await socket.receive()  # the client sends nothing: this returns once it is closed
    finally:
        sending.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await sending
    return socket


async def close_sockets(app: web.Application) -> None:
    for socket in set(app[SOCKETS]):
        await socket.close(code=aiohttp.WSCloseCode.GOING_AWAY, message=b"server shutdown")


def make_app() -> web.Application:
    app = web.Application()
    app[SOCKETS] = weakref.WeakSet()
    app.cleanup_ctx.append(robot_context)
    app.on_shutdown.append(close_sockets)
    app.add_routes(
        [
            web.post("/vacuum", start_vacuum),
            web.get("/actions/{ident}", poll_action),
            web.delete("/actions/{ident}", cancel_action),
            web.get("/battery", battery),
        ]
    )
    return app


async def try_it() -> dict[str, Any]:
    """Serve the app on a free loopback port, call each endpoint as a client would, stop."""
    runner = web.AppRunner(make_app(), access_log=None)  # the demo logs its own calls
    await runner.setup()
    site = web.TCPSite(runner, "127.0.0.1", 0)
    await site.start()
    host, port = runner.addresses[0][:2]
    seen: dict[str, Any] = {}
    async with aiohttp.ClientSession(f"http://{host}:{port}") as client:

        async def call(what: str, method: str, path: str, **params: Any) -> Any:
            async with client.request(method, path, params=params) as response:
                seen[what] = await response.json()
                log.info("%s %s %s -> %d %s", method, path, params, response.status, seen[what])
            return seen[what]

        walk = await call("started", "POST", "/vacuum", rooms=1000)
        await call("gave up", "GET", f"/actions/{walk['id']}", wait=0.2)  # it goes on
        async with client.ws_connect("/battery") as socket:
            seen["battery"] = [await socket.receive_json() for _ in range(3)]
        log.info("GET /battery (websocket) -> %s", seen["battery"])
        await call("cancelled", "DELETE", f"/actions/{walk['id']}")
        short = await call("short", "POST", "/vacuum", rooms=2)
        await call("short after", "GET", f"/actions/{short['id']}", wait=30)
    await runner.cleanup()
    return seen


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, help="serve on 127.0.0.1:PORT until Ctrl-C")
    port = parser.parse_args().port
    if port is None:
        asyncio.run(try_it())
    else:
        web.run_app(make_app(), host="127.0.0.1", port=port)
