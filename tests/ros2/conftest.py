"""ROS 2 tests: real DDS on this machine, plain rclpy nodes written by the tests themselves.

Before rclpy starts, discovery is kept on localhost and a random
``ROS_DOMAIN_ID`` is drawn for the session (inherited by sim-node
subprocesses), so parallel runs never cross-talk. The tests skip, with the
reason, when rclpy is not importable; ``nox -s ros2`` sets
``PYROBOTS_AIO_REQUIRE_ROS2=1``, which makes a missing rclpy an error
instead, and so what a test module asks for through ``ros2_support.require``
(the simulator, a built interface package). These are real-time tests: they
wait on events under generous ``asyncio.timeout`` deadlines, never on sleeps.
"""

from __future__ import annotations

import asyncio
import importlib.util
import os
import random
import threading
import warnings
from typing import TYPE_CHECKING, Any

import pytest
import pytest_asyncio

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Callable, Iterator, Mapping

from ros2_support import REQUIRE, SKIP_REASON, PlainNode

from pyrobots_aio import Robot
from pyrobots_aio.ros2 import attach_ros2

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 101))

if importlib.util.find_spec("rclpy") is None:
    if os.environ.get(REQUIRE) == "1":
        msg = f"{REQUIRE}=1 but rclpy cannot be imported: {SKIP_REASON}"
        raise RuntimeError(msg)
else:
    # rclpy imports lark (through rosidl) when a type support first loads, and lark imports
    # the deprecated sre_parse: imported once here, the warning does not fail a test.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        importlib.import_module("lark")


@pytest.hookimpl(optionalhook=True)
def pytest_asyncio_loop_factories(
    config: pytest.Config, item: pytest.Item
) -> Mapping[str, Callable[[], asyncio.AbstractEventLoop]] | None:
    """A module with ``LOOP_RATE = R`` runs its tests on a loop whose clock runs R times faster.

    Beside a ``sim-node --rate R``: the test's sleeps and timeouts, and the
    robot's clock, then last as long in simulated seconds as they say.
    """
    rate = getattr(getattr(item, "module", None), "LOOP_RATE", None)
    if rate is None:
        return None
    from pyrobots_aio.loops import scaled_loop

    return {f"x{rate}": lambda: scaled_loop(rate)}


@pytest.fixture(autouse=True)
def no_leaked_threads() -> Iterator[None]:
    """Every ROS 2 test ends with the Python threads it started with.

    Except the worker threads of a module's plain rclpy server (its
    ``MultiThreadedExecutor`` starts them as work comes, and stops them with the server);
    a thread still ending gets five seconds.
    """
    before = set(threading.enumerate())
    yield
    left = [
        t
        for t in threading.enumerate()
        if t not in before and not t.name.startswith("ThreadPoolExecutor-")
    ]
    for thread in left:  # one that is ending (asyncio's waitpid thread of a child) ends now
        thread.join(timeout=5.0)
    left = [t for t in left if t.is_alive()]
    assert not left, f"threads outlived the test: {left}"


@pytest_asyncio.fixture
async def plain() -> AsyncIterator[Callable[..., PlainNode]]:
    """Make plain rclpy nodes (``plain("name")``); they are closed when the test ends."""
    made: list[PlainNode] = []

    def make(name: str, **options: Any) -> PlainNode:
        node = PlainNode(name, **options)
        made.append(node)
        return node

    yield make
    for node in made:
        node.close()


@pytest.fixture
def executive() -> Robot:
    """A robot with a ROS 2 node named ``executive`` (not running yet)."""
    robot = Robot()
    attach_ros2(robot, "executive")
    return robot
