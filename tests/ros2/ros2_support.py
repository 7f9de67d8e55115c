"""Helpers of the ROS 2 tests: plain rclpy nodes the tests write themselves, and waits.

``PlainNode`` uses rclpy only, as any other ROS 2 program would; it is how
the tests check that pyrobots_aio interoperates with ROS 2, not only with
itself.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import importlib.util
import os
import re
import subprocess
import sys
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator, Mapping
    from types import ModuleType

REQUIRE = "PYROBOTS_AIO_REQUIRE_ROS2"
"""Set to 1 (as ``nox -s ros2`` does), a missing ROS 2 part fails the tests instead of skipping."""
SKIP_REASON = (
    "the ROS 2 Python wheels are not installed: pip install 'pyrobots-aio[ros2]' "
    "ros-test-msgs ros-std-srvs (nox -s ros2 runs these tests)"
)
DEADLINE = 60.0
"""Seconds any single wait may take: DDS discovery on a loaded 2-core machine can be slow."""
PEER_SILENCE = 10.0
"""Seconds of the wall clock a robot and its sim-node may go without a word from the other.

For the tests whose subject is not that silence (stale odometry and the sim-node's
command timeout have tests of their own). The control loop runs through two processes
in real time, and a loaded machine starves either one: the sim-node stopped for 1 s
at load 12 (stale odometry at ``odom_timeout`` 2 s of a 2x loop), and a test process
held up for 0.6 s of every 0.65 s let the sim-node's 0.5 s command timeout stop the
wheels tick after tick until the drive failed with a `StallError`. Ten times the
longest silence seen, and a dead peer still ends a test with its own error well before
the hang guards (`DEADLINE`, pytest's 120 s).
"""


def silence_options(rate: float) -> tuple[str, ...]:
    """A sim-node's options at ``rate``: its command holds for `PEER_SILENCE` wall seconds."""
    return ("--rate", str(rate), "--cmd-timeout", str(PEER_SILENCE * rate))


def require(module: str, reason: str) -> None:
    """Skip the caller (a test, or its module) with ``reason`` when ``module`` cannot be imported.

    Under ``PYROBOTS_AIO_REQUIRE_ROS2=1`` (``nox -s ros2``, where none may skip) the caller
    fails instead, naming the module: a missing build is an error there, not a quiet skip.
    """
    if os.environ.get(REQUIRE) != "1":
        pytest.importorskip(module, reason=reason)
        return
    try:
        importlib.import_module(module)
    except ImportError as error:
        pytest.fail(f"{REQUIRE}=1 but {module} cannot be imported ({error}): {reason}", False)


def require_rclpy() -> None:
    """The caller needs rclpy (see `require`)."""
    require("rclpy", SKIP_REASON)


def require_sim() -> None:
    """The caller needs the simulator (a sim-node; see `require`)."""
    require("mujoco", "sim-node needs the sim extra: pip install 'pyrobots-aio[sim]'")


def require_interfaces(package: str) -> None:
    """The caller needs an interface package PyPI lacks, built here (see `require`)."""
    require(package, f"it is not built: pyrobots-aio ros2 interfaces build {package}")


async def wait_for(predicate: Callable[[], bool], period: float = 0.02) -> None:
    """Wait until ``predicate()`` (a fact of the ROS graph) holds, under the caller's deadline.

    rclpy offers no event for graph changes (its own ``wait_for_service``
    sleeps and looks again), so this looks again every ``period``.
    """
    while not predicate():  # noqa: ASYNC110 - the graph has no event to wait on
        await asyncio.sleep(period)


class PlainNode:
    """A plain rclpy node of the test's own: its own context, spun on its own thread.

    It uses rclpy only, as any other ROS 2 program would; what it receives
    reaches the test's loop through ``call_soon_threadsafe``.
    """

    def __init__(
        self,
        name: str,
        *,
        threads: int = 1,
        loop: asyncio.AbstractEventLoop | None = None,
        spin: bool = True,
    ) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor

        self.loop = loop or asyncio.get_running_loop()
        self.context = Context()
        self.context.init(args=[])
        self.node = rclpy.create_node(name, context=self.context)
        self.executor: Any = (
            MultiThreadedExecutor(num_threads=threads, context=self.context)
            if threads > 1
            else SingleThreadedExecutor(context=self.context)
        )
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, name=f"plain {name}")
        if spin:
            self.thread.start()

    def spin(self) -> None:
        """Start spinning (for a node made with ``spin=False``)."""
        self.thread.start()

    def knows_client(self, node: str, namespace: str, name: str, *, action: bool) -> bool:
        """Whether this node's view of the graph has ``node``'s client of ``name``."""
        from rclpy.action import get_action_client_names_and_types_by_node
        from rclpy.impl.implementation_singleton import rclpy_implementation

        try:
            if action:
                clients = get_action_client_names_and_types_by_node(self.node, node, namespace)
            else:
                clients = self.node.get_client_names_and_types_by_node(node, namespace)
        except (rclpy_implementation.NodeNameNonExistentError, rclpy_implementation.RCLError):
            return False  # the node is not discovered yet
        return name in dict(clients)

    def to_loop(self, fn: Callable[..., object], *args: object) -> None:
        """From rclpy's thread: run ``fn(*args)`` on the test's loop (if it still runs)."""
        with contextlib.suppress(RuntimeError):  # the loop closed: the test is over
            self.loop.call_soon_threadsafe(fn, *args)

    def inbox(self, topic: str, msg_type: type, qos: Any = 10) -> asyncio.Queue[Any]:
        """Subscribe to ``topic``; every message lands in the returned queue."""
        queue: asyncio.Queue[Any] = asyncio.Queue()
        self.node.create_subscription(
            msg_type, topic, lambda m: self.to_loop(queue.put_nowait, m), qos
        )
        return queue

    def publisher(
        self, topic: str, msg_type: type, qos: Any = 10, *, subscribers: int = 1
    ) -> tuple[Any, asyncio.Event]:
        """A publisher, and an event set once ``subscribers`` subscriptions match it."""
        from rclpy.event_handler import PublisherEventCallbacks

        matched = asyncio.Event()

        def on_matched(info: Any) -> None:
            if info.current_count >= subscribers:
                self.to_loop(matched.set)

        events = PublisherEventCallbacks(matched=on_matched)
        return self.node.create_publisher(msg_type, topic, qos, event_callbacks=events), matched

    def close(self) -> None:
        """Stop spinning; destroy the node and the context."""
        self.executor.shutdown()
        if self.thread.is_alive():
            self.thread.join()
        self.node.destroy_node()
        self.context.try_shutdown()


async def next_where(queue: asyncio.Queue[Any], predicate: Callable[[Any], bool]) -> Any:
    """The next message from ``queue`` for which ``predicate`` holds (others are skipped)."""
    while True:
        message = await queue.get()
        if predicate(message):
            return message


async def meet(robot: Any, server: PlainNode, name: str, interface: type) -> None:
    """Wait until the robot sees ``server``'s server of ``name`` and the server sees its client.

    A DDS server answers a request only once it has matched the client's
    reader (rmw waits 100 ms for that, then drops the response): on a loaded
    machine, a test waits for both views of the graph before the first request.
    """
    await robot.ros2.wait_for_server(name, interface)
    node, namespace, action = robot.ros2.name, robot.ros2.namespace, hasattr(interface, "Goal")
    await wait_for(lambda: server.knows_client(node, namespace, name, action=action))


async def run_script(script: Path, *args: str) -> tuple[int, str, str]:
    """Run ``python script args`` to its end (killed if cancelled): exit code, stdout, stderr."""
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        str(script),
        *args,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    try:
        out, err = await process.communicate()
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()
    return process.returncode or 0, out.decode(), err.decode()


SIM_NODE = [sys.executable, "-m", "pyrobots_aio.cli", "sim-node"]


@contextlib.contextmanager
def sim_node_process(
    *args: str, env: Mapping[str, str] | None = None
) -> Iterator[subprocess.Popen[bytes]]:
    """A sim-node process (``args``: its options), up and ready; killed if still running after."""
    process = subprocess.Popen(
        [*SIM_NODE, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    )
    try:
        assert process.stdout is not None
        ready = process.stdout.readline()
        if b" ready " not in ready:
            process.kill()
            _, err = process.communicate()
            raise AssertionError((ready + err).decode(errors="replace"))
        yield process
    finally:
        if process.poll() is None:
            process.kill()
        process.communicate()


def load_suite(name: str, file: str | None = None) -> ModuleType:
    """The module ``tests/motion/<file or name>.py`` (the shared motion suite), imported once."""
    path = Path(__file__).parent.parent / "motion" / f"{file or name}.py"
    module = sys.modules.get(name)
    if module is not None and Path(module.__file__ or "") == path:
        return module
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def assert_stale_error(error: BaseException, namespace: str, timeout: float) -> None:
    """``error`` is the stale-odometry MotionError for ``namespace``, aged >= ``timeout``."""
    found = re.fullmatch(
        rf"odometry on {namespace}/odom is stale: no message for (\d+\.\d\d) s \(odom_timeout "
        rf"{timeout:g} s\); the base was stopped \(zero Twist on {namespace}/cmd_vel\) and "
        r"refuses to move until odometry comes back — is its driver running\?",
        str(error),
    )
    assert found is not None, str(error)
    assert float(found.group(1)) >= timeout - 0.005  # (the age is shown rounded)
