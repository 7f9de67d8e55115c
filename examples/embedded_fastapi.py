"""Embedded in FastAPI: the robot lives in the app's lifespan; endpoints drive it.

``async with Robot()`` is entered in the lifespan and kept on ``app.state``: the
robot starts before the first request, stops after the last one, and no task
outlives it (the lifespan logs the tasks left once the robot is out: none).

    POST   /patrol?laps=N          start an action; answer its id at once (202)
    GET    /actions/{id}?wait=S    long-poll: wait up to S s; giving up leaves it running
    DELETE /actions/{id}           cancel an action; answer once its cleanup is over
    POST   /dock?seconds=T&deadline=S  run an action inside the request, owning it:
                                   past the deadline the request gives up and cancels it (504)
    POST   /stop                   a plain ``def`` endpoint (FastAPI runs it in a worker
                                   thread): it hands its work to the robot's loop
    GET    /battery?count=N        Server-Sent Events: the level, then each change
    POST   /simulate?distance=D    a dry run in the MuJoCo simulator, in lockstep
                                   virtual time, in a thread beside the service

uvicorn waits for open responses before it runs the lifespan's shutdown: a
battery stream without ``count`` keeps Ctrl-C waiting until its client leaves
(or until ``--timeout-graceful-shutdown`` cuts it).

Run: ``python examples/embedded_fastapi.py`` serves the app on a free loopback
port, calls each endpoint as a client would, and stops. Serve it until Ctrl-C
as a deployment does: ``uvicorn --app-dir examples embedded_fastapi:app``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from typing import TYPE_CHECKING, Annotated, Any

import httpx
import uvicorn
from fastapi import Depends, FastAPI, HTTPException, Query, Request
from fastapi.responses import StreamingResponse

import pyrobots_aio.sim
from pyrobots_aio import ActionHandle, ActionInterrupted, Outcome, Robot, action
from pyrobots_aio.cli import install_console_handler
from pyrobots_aio.sim import SimRobot

if TYPE_CHECKING:
    from collections.abc import AsyncIterator

log = logging.getLogger("embedded_fastapi")


@action
async def patrol(robot: Robot, laps: int) -> int:
    """Drive ``laps`` laps of 0.1 s; each costs one percent of the battery."""
    for _ in range(laps):
        await robot.sleep(0.1)
        robot.state.battery = round(robot.state.battery - 0.01, 2)
    return laps


@action
async def dock(robot: Robot, seconds: float) -> str:
    await robot.sleep(seconds)
    robot.state.docked = True
    return "docked"


@contextlib.asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    before = asyncio.all_tasks()
    async with Robot() as robot:
        robot.state.update(battery=1.0, docked=False)
        app.state.robot = robot
        app.state.actions = {}
        log.info("robot started")
        yield
    left = sorted(task.get_name() for task in asyncio.all_tasks() - before)
    log.info("robot stopped; tasks left: %s", left or "none")


app = FastAPI(lifespan=lifespan)


async def get_robot(request: Request) -> Robot:
    robot: Robot = request.app.state.robot
    return robot


RobotDep = Annotated[Robot, Depends(get_robot)]


def keep(request: Request, handle: ActionHandle[Any]) -> ActionHandle[Any]:
    """Remember ``handle`` under its id, for the endpoints that take an id."""
    request.app.state.actions[handle.id] = handle
    return handle


def find(request: Request, ident: int) -> ActionHandle[Any]:
    handle: ActionHandle[Any] | None = request.app.state.actions.get(ident)
    if handle is None:
        raise HTTPException(404, f"no action #{ident}")
    return handle


def describe(handle: ActionHandle[Any]) -> dict[str, Any]:
    answer = {"id": handle.id, "name": handle.name, "state": handle.state.value}
    answer["outcome"] = handle.outcome.value
    if handle.outcome is Outcome.SUCCEEDED:
        answer["result"] = handle.result()
    if handle.cancel_reason is not None:
        answer["cancel_reason"] = handle.cancel_reason
    return answer


@app.post("/patrol", status_code=202)
async def start_patrol(request: Request, robot: RobotDep, laps: int = 3) -> dict[str, Any]:
    return describe(keep(request, patrol(robot, laps)))


@app.get("/actions/{ident}")
async def poll_action(
    request: Request, ident: int, wait: Annotated[float, Query(ge=0, le=60)] = 0
) -> dict[str, Any]:
    handle = find(request, ident)
    with contextlib.suppress(TimeoutError):
        async with asyncio.timeout(wait):
            await handle.wait_done()  # not owning: giving up leaves the action running
    return describe(handle)


@app.delete("/actions/{ident}")
async def cancel_action(request: Request, ident: int) -> dict[str, Any]:
    handle = find(request, ident)
    handle.cancel("cancelled over HTTP")
    await handle.wait_done()  # its cleanup is bounded by the robot's cancel_grace
    return describe(handle)


@app.post("/dock")
async def run_dock(
    request: Request, robot: RobotDep, seconds: float = 0.5, deadline: float = 5.0
) -> dict[str, Any]:
    handle = keep(request, dock(robot, seconds))
    try:
        async with asyncio.timeout(deadline):
            await handle  # owning: when the deadline cancels this wait, it cancels the action
    except TimeoutError:
        detail = {"error": f"not done within {deadline} s", **describe(handle)}
        raise HTTPException(504, detail) from None
    except ActionInterrupted as stop:
        raise HTTPException(409, f"dock#{handle.id} interrupted: {stop.reason}") from None
    return describe(handle)


async def stop_everything(robot: Robot) -> int:
    running = len(robot.handles())
    await robot.cancel_all("stop button")
    return running


@app.post("/stop")
def stop(request: Request) -> dict[str, int]:
    """A ``def`` endpoint runs in a worker thread: it hands its work to the robot's loop."""
    robot: Robot = request.app.state.robot
    return {"stopped": robot.run_threadsafe(stop_everything(robot)).result(timeout=30)}


@app.get("/battery")
async def battery(
    robot: RobotDep, count: Annotated[int | None, Query(ge=1)] = None
) -> StreamingResponse:
    async def events() -> AsyncIterator[str]:
        # subscribed before the level is read: no change is missed
        async with contextlib.aclosing(robot.watch("battery")) as changes:
            yield f"data: {robot.state.battery}\n\n"
            sent = 0
            async for level in changes:  # ends when the robot stops
                yield f"data: {level}\n\n"
                sent += 1
                if sent == count:
                    break

    return StreamingResponse(events(), media_type="text/event-stream")


async def dry_run(distance: float) -> dict[str, Any]:
    """Undock and drive ``distance`` metres in the simulator (lockstep virtual time)."""
    async with SimRobot(seed=1) as sim:
        await sim.undock()
        outcome = await sim.drive_distance(distance).wait_done()
        return {"outcome": outcome.value, "sim_seconds": round(sim.time(), 2)}


@app.post("/simulate")
async def simulate(distance: float = 0.5) -> dict[str, Any]:
    # sim.run drives a virtual-time loop of its own: not in this loop, in a thread beside it
    report: dict[str, Any] = await asyncio.to_thread(pyrobots_aio.sim.run, dry_run, distance)
    return report


async def try_it() -> dict[str, Any]:
    """Serve the app on a free loopback port, call each endpoint as a client would, stop."""
    listener = socket.create_server(("127.0.0.1", 0))
    server = uvicorn.Server(uvicorn.Config(app, log_config=None, log_level="warning"))
    serving = asyncio.create_task(server.serve(sockets=[listener]))
    url = "http://127.0.0.1:{}".format(*listener.getsockname()[1:])
    seen: dict[str, Any] = {}
    async with httpx.AsyncClient(base_url=url, timeout=60) as client:

        async def call(what: str, method: str, path: str, **params: Any) -> Any:
            response = await client.request(method, path, params=params)
            seen[what] = response.json()
            log.info("%s %s %s -> %d %s", method, path, params, response.status_code, seen[what])
            return seen[what]

        walk = await call("started", "POST", "/patrol", laps=1000)
        await call("gave up", "GET", f"/actions/{walk['id']}", wait=0.2)  # it goes on
        async with client.stream("GET", "/battery", params={"count": 2}) as stream:
            seen["battery"] = [float(line[6:]) async for line in stream.aiter_lines() if line]
        log.info("GET /battery?count=2 -> %s", seen["battery"])
        late = await call("late", "POST", "/dock", seconds=60, deadline=0.2)  # cancelled
        await call("late after", "GET", f"/actions/{late['detail']['id']}", wait=30)
        await call("simulated", "POST", "/simulate", distance=0.5)
        await call("stop", "POST", "/stop")
        await call("stopped", "GET", f"/actions/{walk['id']}")
        short = await call("short", "POST", "/patrol", laps=2)
        await call("short after", "GET", f"/actions/{short['id']}", wait=30)
    server.should_exit = True
    await serving
    return seen


if __name__ == "__main__":
    install_console_handler(logging.INFO)
    logging.getLogger("httpx").setLevel(logging.WARNING)  # the demo logs its own calls
    asyncio.run(try_it())
