"""``Robot(serve=PORT)``: the running robot, live in Foxglove, over its WebSocket protocol.

The live view publishes the channels of the MCAP recorder (`channels`): the
executive's events, each state key at each write, the pose, ``/tf``, log
lines and a simulated robot's arena, through Foxglove's own SDK (the ``live``
extra, ``foxglove-sdk``), on 127.0.0.1 unless told otherwise. The ``time`` of
its events and samples counts seconds from the robot's start. The arena is
sent to each client that subscribes to it (it never changes; a client that
connects late still gets it). The SDK speaks the ``foxglove.sdk.v1``
subprotocol only, which the Foxglove app offers; a client that offers only
``foxglove.websocket.v1`` (older Foxglove Studio, Lichtblick) is refused with
HTTP 400, and the server's log says why (`HANDSHAKE_HINT`). It runs from
``async with robot`` to its end, when its server is stopped and its port
closed (unless it was given: ``Robot(serve=LiveView(PORT))``). (The SDK
serves from one runtime of native threads per process, shared by every server,
idle once they stop, shut down by the SDK at exit: no Python thread, and none
more per robot.)
Only the state writes and events of the robot's loop thread are published, in
that thread; publishing costs a JSON encoding and a queue push per message.
"""

from __future__ import annotations

import datetime
import logging
import socket
import time
from typing import TYPE_CHECKING, Any

from .._core._json import strict_json
from .._exceptions import PyRobotsError
from ._arena import ARENA, SCENE_UPDATE, floor_plan
from ._channels import FIXED_CHANNELS, SCHEMAS, FoxgloveChannels, LogForwarder
from ._sampling import StateSampler

if TYPE_CHECKING:
    from types import ModuleType

    from .._core._instrument import ExecEvent
    from ..poses import Pose2D
    from ._channels import Message
    from ._source import TelemetrySource

_log = logging.getLogger("pyrobots_aio.live")
LOGGER = "pyrobots_aio"
"""The logger whose records are published on ``/pyrobots/log``."""

CLOSE_LIMIT = 2.0
"""Seconds `LiveView.stop` waits at most for the SDK to let go of the port."""
SUBPROTOCOL = "foxglove.sdk.v1"
"""The WebSocket subprotocol the SDK's server speaks (it refuses a client not offering it)."""
HANDSHAKE_HINT = (
    f": the live view speaks the {SUBPROTOCOL} WebSocket subprotocol, which the Foxglove app "
    "offers; a client that offers only foxglove.websocket.v1 (older Foxglove Studio and "
    "Lichtblick releases) gets HTTP 400 'Missing expected sec-websocket-protocol header': "
    "update it"
)
"""What the SDK's 'handshake failed' log line is told, for whoever reads the server's log."""


class _HandshakeHint(logging.Filter):
    """Completes the SDK's ``Dropping client ...: handshake failed`` with the likely cause."""

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if text.endswith("handshake failed"):
            record.msg, record.args = text + HANDSHAKE_HINT, None
        return True


_SDK_SERVER_LOG = logging.getLogger("foxglove.websocket.server")
_SDK_SERVER_LOG.addFilter(_HandshakeHint())  # one filter, on the SDK's own logger only


def _port_free(host: str, port: int) -> bool:
    """Whether a new server could listen on ``host:port`` now (no connection is made)."""
    with socket.socket() as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((host, port))
        except OSError:
            return False
        return True


def _wait_port_free(host: str, port: int) -> None:
    """Wait (briefly, bounded) until the port is free again.

    The SDK's ``stop()`` returns before its runtime closes the listening socket
    (about a millisecond later); without this wait a robot started right after
    on the same port could find it taken.
    """
    deadline = time.monotonic() + CLOSE_LIMIT
    while not _port_free(host, port):
        if time.monotonic() > deadline:
            _log.warning("the live view's port %s:%s is still taken after stop", host, port)
            return
        time.sleep(0.001)


def _sdk() -> ModuleType:
    try:
        import foxglove
    except ImportError as exc:
        msg = (
            "Robot(serve=...) needs Foxglove's SDK, which is optional: install it with "
            'pip install -e ".[live]" from a checkout (or pip install foxglove-sdk)'
        )
        raise PyRobotsError(msg) from exc
    return foxglove


def checked_port(port: object) -> int:
    """``port`` if it is a TCP port number (0: any free port).

    Raises:
        ValueError: It is not an integer from 0 to 65535.
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        msg = f"serve must be a TCP port number from 0 to 65535 (0: any free port), got {port!r}"
        raise ValueError(msg)
    return port


class _ArenaOnSubscribe:
    """A server listener: each client that subscribes to the arena gets it then.

    The SDK calls it on one of its own threads; it only logs one message, made
    beforehand, on a channel the SDK makes safe to log on from any thread.
    """

    def __init__(self) -> None:
        self.channel: Any = None
        self.message: Message | None = None
        self.latest = 0
        """The time of the latest message sent (ns since 1970): the arena's, when resent."""

    def on_subscribe(self, client: object, channel: Any) -> None:
        arena, message = self.channel, self.message
        if arena is not None and message is not None and channel.topic == ARENA:
            arena.log(message.data, log_time=max(message.log_time, self.latest))


class LiveView:
    """A Foxglove WebSocket server streaming one robot's run while it runs.

    Args:
        port: The TCP port (0: any free one; `port` tells which once started).
        host: The address to listen on (default: this machine only).
    """

    def __init__(self, port: int, host: str = "127.0.0.1") -> None:
        self._foxglove = _sdk()
        self.requested = checked_port(port)
        self.host = host
        self._server: Any = None
        self._context: Any = None
        self._channels: dict[str, Any] = {}
        self._robot: TelemetrySource | None = None
        self._encoder = FoxgloveChannels(0, 0.0)
        self._sampler = StateSampler(self._samples)
        self._forwarder: LogForwarder | None = None
        self._arena = _ArenaOnSubscribe()

    @property
    def port(self) -> int | None:
        """The port served on, while serving."""
        return None if self._server is None else int(self._server.port)

    def start(self, robot: TelemetrySource) -> None:
        """Serve ``robot``'s channels (start the server unless it is serving already).

        Raises:
            PyRobotsError: The server cannot listen (the port is taken ...), or
                the view streams another robot now.
        """
        if self._robot is not None:
            msg = f"{self!r} streams {self._robot!r} already; give {robot!r} a LiveView of its own"
            raise PyRobotsError(msg)
        if self._server is None:
            self._listen(f"pyrobots_aio {type(robot).__name__}")
        # Wall-clock start, so that Foxglove shows the date; never used for timing.
        origin = round(datetime.datetime.now(datetime.UTC).timestamp() * 1e9)
        self._sampler = StateSampler(self._samples)
        self._encoder = FoxgloveChannels(origin, robot.time(), since_start=True)
        shapes = floor_plan(robot)
        self._arena.message = self._encoder.arena(shapes) if shapes else None
        if shapes:
            self._arena.channel = self._channel(ARENA, SCENE_UPDATE)
        self._robot = robot
        robot.instruments.add(self)
        self._sampler.start(robot)
        self._encoder.frame = self._sampler.pose_frame or "base_link"
        self._forwarder = LogForwarder(self._encoder, self._send)
        logging.getLogger(LOGGER).addHandler(self._forwarder)

    def _listen(self, name: str) -> None:
        fox = self._foxglove
        self._context = fox.Context()
        try:
            self._server = fox.start_server(
                name=name,
                host=self.host,
                port=self.requested,
                context=self._context,
                server_listener=self._arena,
            )
        except Exception as exc:  # the SDK raises RuntimeError and others
            self._context = None
            msg = f"cannot serve the live view on {self.host}:{self.requested}: {exc}"
            raise PyRobotsError(msg) from exc
        for topic, schema in FIXED_CHANNELS.items():
            self._channel(topic, schema)
        _log.info("live view on ws://%s:%s (open it in Foxglove)", self.host, self.port)

    def detach(self) -> None:
        """Stop streaming the robot, and keep serving: clients stay connected with what they got.

        A robot detaches the `LiveView` it was given when it stops (``Robot(serve=view)``).
        """
        if self._forwarder is not None:
            logging.getLogger(LOGGER).removeHandler(self._forwarder)
            self._forwarder = None
        self._sampler.stop()
        if self._robot is not None:
            self._robot.instruments.remove(self)
            self._robot = None

    def stop(self) -> None:
        """Stop streaming and serving; nothing of the server is left running."""
        self.detach()
        server, self._server = self._server, None
        if server is not None:
            port = int(server.port)
            server.stop()
            _wait_port_free(self.host, port)
        self._arena.channel = self._arena.message = None
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
        self._context = None

    def _channel(self, topic: str, schema: str) -> Any:
        channel = self._channels.get(topic)
        if channel is None:
            fox = self._foxglove
            definition = fox.Schema(
                name=schema, encoding="jsonschema", data=strict_json(SCHEMAS[schema])
            )
            channel = fox.Channel(
                topic, schema=definition, message_encoding="json", context=self._context
            )
            self._channels[topic] = channel
        return channel

    def _send(self, message: Message) -> None:
        if self._server is None:
            return
        self._arena.latest = message.log_time
        self._channel(message.topic, message.schema).log(message.data, log_time=message.log_time)

    def on_event(self, event: ExecEvent) -> None:
        """Publish one executive event (the robot's instruments call this)."""
        for message in self._encoder.event(event):
            self._send(message)

    def _samples(self, time: float, values: dict[str, object], pose: Pose2D | None) -> None:
        for message in self._encoder.samples(time, values, pose):
            self._send(message)

    def __repr__(self) -> str:
        where = f"ws://{self.host}:{self.port}" if self._server is not None else "stopped"
        return f"<LiveView {where}>"
