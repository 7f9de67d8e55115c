"""``Robot(serve=PORT)``: a live view over Foxglove's WebSocket protocol, tested with a real client.

The client speaks the protocol as Foxglove does (``foxglove.sdk.v1``): it
reads the server's channels, subscribes, and decodes the binary message frames
(opcode 1, subscription id, time, JSON payload).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import re
import socket
import struct
import sys
import threading
from typing import Any

import pytest
import websockets

from foxglove_scene import check_scene
from pyrobots_aio import PyRobotsError, Robot
from pyrobots_aio.sim import SimRobot
from pyrobots_aio.telemetry import _live

PROTOCOL = websockets.Subprotocol("foxglove.sdk.v1")


class FoxgloveClient:
    """A minimal Foxglove WebSocket client: channels by topic, and messages by topic."""

    def __init__(self, ws: Any) -> None:
        self.ws = ws
        self.channels: dict[str, dict[str, Any]] = {}
        self.received: dict[str, list[dict[str, Any]]] = {}
        self._topics: dict[int, str] = {}

    async def read_until(self, done: Any) -> None:
        """Read frames until ``done(self)`` is true."""
        while not done(self):
            frame = await self.ws.recv()
            if isinstance(frame, str):
                body = json.loads(frame)
                if body["op"] == "advertise":
                    self.channels |= {c["topic"]: c for c in body["channels"]}
            else:
                opcode, subscription, _ = struct.unpack_from("<BIQ", frame)
                assert opcode == 1  # a message data frame
                topic = self._topics[subscription]
                self.received.setdefault(topic, []).append(json.loads(frame[13:]))

    async def subscribe(self, *topics: str) -> None:
        subscriptions = []
        for topic in topics:
            ident = len(self._topics) + 1
            self._topics[ident] = topic
            subscriptions.append({"id": ident, "channelId": self.channels[topic]["id"]})
        await self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))


class Subscriptions:
    """The topics the live view's server has taken a subscription to, as its listener hears.

    The SDK tells the server's listener of each subscription once it is in place (the
    listener sends the arena to the new subscriber then): a message logged after that
    reaches the client.
    """

    def __init__(self) -> None:
        self.topics: list[str] = []
        self._lock = threading.Lock()
        self._waiter: tuple[asyncio.AbstractEventLoop, asyncio.Event] | None = None

    def heard(self, topic: str) -> None:
        """Called in the SDK's thread: ``topic`` has a new subscription."""
        with self._lock:
            self.topics.append(topic)
            waiter = self._waiter
        if waiter is not None:
            loop, changed = waiter
            loop.call_soon_threadsafe(changed.set)

    async def wait_for(self, *topics: str) -> None:
        """Wait until each of ``topics`` has a subscription."""
        changed = asyncio.Event()
        with self._lock:
            self._waiter = (asyncio.get_running_loop(), changed)
        async with asyncio.timeout(30):  # a hang guard, not a timing
            while True:
                with self._lock:
                    if set(topics) <= set(self.topics):
                        self._waiter = None
                        return
                await changed.wait()
                changed.clear()


@pytest.fixture
def subscriptions(monkeypatch: pytest.MonkeyPatch) -> Subscriptions:
    """The subscriptions the live views' servers take from now on."""
    seen, on_subscribe = Subscriptions(), _live._ArenaOnSubscribe.on_subscribe

    def hearing(self: _live._ArenaOnSubscribe, client: object, channel: Any) -> None:
        on_subscribe(self, client, channel)
        seen.heard(channel.topic)

    monkeypatch.setattr(_live._ArenaOnSubscribe, "on_subscribe", hearing)
    return seen


def _refused(port: int) -> bool:
    """Whether nothing listens on the port any more.

    The server's port is an ephemeral one, so the probe's own source port may be
    the very same number: Linux then joins the socket to itself (a TCP
    simultaneous open) and the connection "succeeds" with no server there.
    """
    with socket.socket() as probe:
        if probe.connect_ex(("127.0.0.1", port)) != 0:
            return True
        return bool(probe.getsockname() == probe.getpeername())


def _python_threads() -> set[threading.Thread]:
    """The threads Python started (not the SDK's native ones that once called into Python)."""
    return {t for t in threading.enumerate() if not isinstance(t, threading._DummyThread)}


def _native_threads() -> int:
    """The threads no Python code started (the SDK's), by their OS name.

    Python's own threads keep the process's name here; counting every OS thread
    would also count a joined Python thread the OS still lists for a moment.
    """
    with open("/proc/self/comm") as own:
        python = own.read()
    count = 0
    for task in os.listdir("/proc/self/task"):
        with contextlib.suppress(FileNotFoundError), open(f"/proc/self/task/{task}/comm") as comm:
            count += comm.read() != python  # (a thread that just ended has no file)
    return count


@pytest.mark.asyncio
async def test_a_client_subscribes_and_receives_pose_and_action_messages(
    subscriptions: Subscriptions,
) -> None:
    threads = _python_threads()
    robot = SimRobot(realtime=True, serve=0)
    async with robot:
        assert robot.live is not None
        port = robot.live.port
        assert port is not None
        assert repr(robot.live) == f"<LiveView ws://127.0.0.1:{port}>"
        async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[PROTOCOL]) as ws:
            client = FoxgloveClient(ws)
            await asyncio.wait_for(
                client.read_until(
                    lambda c: {"/pyrobots/pose", "/pyrobots/actions"} <= set(c.channels)
                ),
                30,  # a hang guard, not a timing
            )
            pose, actions = client.channels["/pyrobots/pose"], client.channels["/pyrobots/actions"]
            assert (pose["schemaName"], pose["encoding"]) == ("foxglove.PoseInFrame", "json")
            assert json.loads(pose["schema"])["title"] == "foxglove.PoseInFrame"
            assert actions["schemaName"] == "pyrobots_aio.ExecEvent"
            assert client.channels["/tf"]["schemaName"] == "foxglove.FrameTransforms"
            assert client.channels["/pyrobots/log"]["schemaName"] == "foxglove.Log"
            await client.subscribe("/pyrobots/pose", "/pyrobots/actions")
            # the subscription is in place before the action starts
            await subscriptions.wait_for("/pyrobots/pose", "/pyrobots/actions")
            walk = robot.undock()
            await asyncio.wait_for(
                client.read_until(
                    lambda c: (
                        len(c.received.get("/pyrobots/pose", ())) >= 5
                        and len(c.received.get("/pyrobots/actions", ())) >= 2
                    )
                ),
                30,
            )
            walk.cancel("test over")
            await walk.wait_done()
    poses = client.received["/pyrobots/pose"]
    assert {p["frame_id"] for p in poses} == {"map"}
    assert poses[-1]["pose"]["position"]["x"] > -1.728  # moving away from the dock
    first = client.received["/pyrobots/actions"][0]
    assert (first["kind"], first["name"]) == ("action.spawned", "undock")
    # stopped with the robot: the port is closed, and no Python thread is left
    assert _refused(port)
    assert _python_threads() == threads


@pytest.mark.asyncio
async def test_each_robot_stops_its_server_and_leaves_no_thread() -> None:
    counts, closed = [], []
    for _ in range(3):
        async with Robot(serve=0) as robot:
            assert robot.live is not None
            port = robot.live.port
        assert port is not None
        closed.append(_refused(port))  # at once: later, another socket may take the port
        counts.append(_native_threads())
    assert closed == [True, True, True]
    # The SDK's runtime (native, idle, shut down at exit) is shared: no growth per robot.
    assert counts[0] > 0  # the count sees the SDK's threads
    assert counts[0] == counts[1] == counts[2]


@pytest.mark.asyncio
async def test_a_plain_robot_streams_its_state_timed_from_its_start(
    subscriptions: Subscriptions,
) -> None:
    loop = asyncio.get_running_loop()
    robot = Robot(serve=0)
    before = loop.time()  # the machine's monotonic clock: hours or days, not seconds of a run
    async with robot:
        entered = loop.time()
        assert robot.live is not None
        assert robot.live.port is not None
        url = f"ws://127.0.0.1:{robot.live.port}"
        async with websockets.connect(url, subprotocols=[PROTOCOL]) as ws:
            client = FoxgloveClient(ws)
            robot.state.speed = 0.0
            await asyncio.wait_for(
                client.read_until(lambda c: "/pyrobots/state/speed" in c.channels), 30
            )
            await client.subscribe("/pyrobots/state/speed")
            await subscriptions.wait_for("/pyrobots/state/speed")
            robot.state.speed = 0.5
            written = robot.state.timestamp("speed")
            await asyncio.wait_for(
                client.read_until(lambda c: "/pyrobots/state/speed" in c.received), 30
            )
    (sample,) = client.received["/pyrobots/state/speed"]
    assert (sample["key"], sample["value"]) == ("speed", 0.5)
    # the robot started between `before` and `entered`: the sample's time is the write's since then
    assert written - entered <= sample["time"] <= written - before


async def _arena(port: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """The arena's channel, and the scene a client gets when it subscribes to it."""
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=[PROTOCOL]) as ws:
        client = FoxgloveClient(ws)
        await asyncio.wait_for(client.read_until(lambda c: "/pyrobots/arena" in c.channels), 30)
        await client.subscribe("/pyrobots/arena")
        await asyncio.wait_for(client.read_until(lambda c: "/pyrobots/arena" in c.received), 30)
    (scene,) = client.received["/pyrobots/arena"]
    return client.channels["/pyrobots/arena"], scene


@pytest.mark.asyncio
async def test_each_client_gets_the_arena_when_it_subscribes() -> None:
    robot = SimRobot(realtime=True, serve=0)
    async with robot:
        assert robot.live is not None
        port = robot.live.port
        assert port is not None
        channel, scene = await _arena(port)
        assert channel["schemaName"] == "foxglove.SceneUpdate"
        assert json.loads(channel["schema"])["title"] == "foxglove.SceneUpdate"
        check_scene(scene, robot.world.floor_plan())
        _, again = await _arena(port)  # a client that comes later gets it too
        assert again == scene


@pytest.mark.parametrize(
    "offered", [["foxglove.websocket.v1"], ["foxglove.websocket.v1", "foxglove.sdk.v1"]]
)
@pytest.mark.asyncio
async def test_a_client_must_offer_foxglove_sdk_v1(offered: list[str]) -> None:
    """Older Foxglove clients offer only foxglove.websocket.v1: refused, and the log says why."""
    loop = asyncio.get_running_loop()
    refused: asyncio.Future[str] = loop.create_future()

    class Hint(logging.Handler):  # the SDK logs from one of its own threads
        def emit(self, record: logging.LogRecord) -> None:
            text = record.getMessage()
            loop.call_soon_threadsafe(lambda: refused.done() or refused.set_result(text))

    sdk_log = logging.getLogger("foxglove.websocket.server")
    handler = Hint(logging.ERROR)
    sdk_log.addHandler(handler)
    try:
        async with Robot(serve=0) as robot:
            assert robot.live is not None
            url = f"ws://127.0.0.1:{robot.live.port}"
            protocols = [websockets.Subprotocol(p) for p in offered]
            if "foxglove.sdk.v1" in offered:  # what the Foxglove app offers
                async with websockets.connect(url, subprotocols=protocols) as ws:
                    assert ws.subprotocol == "foxglove.sdk.v1"
                    assert json.loads(await ws.recv())["op"] == "serverInfo"
                return
            with pytest.raises(websockets.InvalidStatus) as info:
                await websockets.connect(url, subprotocols=protocols)
            line = await asyncio.wait_for(refused, 30)  # a hang guard
    finally:
        sdk_log.removeHandler(handler)
    response = info.value.response
    assert (response.status_code, bytes(response.body)) == (
        400,
        b"Missing expected sec-websocket-protocol header",
    )
    assert re.fullmatch(r"Dropping client 127\.0\.0\.1:\d+: handshake failed: (.*)", line)
    assert line.endswith(
        ": the live view speaks the foxglove.sdk.v1 WebSocket subprotocol, which the Foxglove "
        "app offers; a client that offers only foxglove.websocket.v1 (older Foxglove Studio and "
        "Lichtblick releases) gets HTTP 400 'Missing expected sec-websocket-protocol header': "
        "update it"
    )


@pytest.mark.parametrize("port", [-1, 65536, "8765", 1.5, True])
def test_a_bad_port_is_refused(port: object) -> None:
    with pytest.raises(ValueError, match=r"serve must be a TCP port number from 0 to 65535"):
        Robot(serve=port)  # type: ignore[arg-type]


@pytest.mark.asyncio
async def test_a_taken_port_is_a_clear_error() -> None:
    async with Robot(serve=0) as first:
        assert first.live is not None
        taken = first.live.port
        second = Robot(serve=taken)
        with pytest.raises(
            PyRobotsError, match=rf"cannot serve the live view on 127\.0\.0\.1:{taken}"
        ):
            async with second:
                pass
        assert not second.is_running


def test_without_the_sdk_the_error_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "foxglove", None)  # as if foxglove-sdk were not installed
    with pytest.raises(PyRobotsError) as info:
        Robot(serve=8765)
    assert str(info.value) == (
        "Robot(serve=...) needs Foxglove's SDK, which is optional: install it with "
        'pip install -e ".[live]" from a checkout (or pip install foxglove-sdk)'
    )
