"""Embedded: the robot inside an existing asyncio service.

A small HTTP service (stdlib ``asyncio.start_server``) already runs its own
tasks; the robot lives beside them in the same loop. ``GET /actions`` reports
the running actions as JSON; ``POST /patrol`` starts one. The script starts
the service on a free loopback port, talks to it as a client would, and
shuts everything down cleanly.

Run: ``python examples/embedded.py``
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging

from pyrobots_aio import Robot, action
from pyrobots_aio.cli import install_console_handler


@action
async def patrol(robot: Robot, laps: int) -> int:
    for _ in range(laps):
        await robot.sleep(0.2)
    return laps


class Service:
    """The existing application: an HTTP endpoint plus a heartbeat task."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.heartbeats = 0

    async def heartbeat(self) -> None:
        while True:
            self.heartbeats += 1
            await asyncio.sleep(0.05)

    async def handle(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        request = (await reader.readline()).decode().split()
        while (await reader.readline()).strip():
            pass  # skip the headers
        method, path = request[0], request[1]
        if (method, path) == ("GET", "/actions"):
            body: object = [
                {"id": i.id, "name": i.name, "state": i.state.value, "parent": i.parent}
                for i in self.robot.running()
            ]
            status = "200 OK"
        elif (method, path) == ("POST", "/patrol"):
            body = {"started": patrol(self.robot, 3).id}
            status = "202 Accepted"
        else:
            body, status = {"error": f"no route {method} {path}"}, "404 Not Found"
        payload = json.dumps(body).encode()
        head = f"HTTP/1.1 {status}\r\nContent-Type: application/json\r\n"
        writer.write(f"{head}Content-Length: {len(payload)}\r\n\r\n".encode() + payload)
        await writer.drain()
        writer.close()
        await writer.wait_closed()


async def request(port: int, method: str, path: str) -> tuple[str, object]:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(f"{method} {path} HTTP/1.1\r\nHost: robot\r\n\r\n".encode())
    await writer.drain()
    response = await reader.read()
    writer.close()
    await writer.wait_closed()
    head, _, body = response.decode().partition("\r\n\r\n")
    return head.splitlines()[0], json.loads(body)


async def main() -> list[object]:
    answers: list[object] = []
    async with Robot() as robot:
        service = Service(robot)
        beat = asyncio.create_task(service.heartbeat())
        server = await asyncio.start_server(service.handle, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        async with server:
            for method, path in [("POST", "/patrol"), ("GET", "/actions"), ("GET", "/nope")]:
                status, body = await request(port, method, path)
                print(f"{method} {path} -> {status}: {body}")
                answers.append(body)
            await robot.sleep(0.7)
            status, body = await request(port, "GET", "/actions")
            print(f"GET /actions after the patrol -> {body}")
            answers.append(body)
        beat.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await beat
        print(f"the service's own heartbeat ran {service.heartbeats} times meanwhile")
    return answers


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    asyncio.run(main())
