"""sim-node as a ROS 2 citizen: ``--ros-args``, parameters, ``/rosout``, a NaN flood, discovery.

Each test runs sim-node in a real subprocess and looks at it the way ROS 2
tools do (a plain rclpy node: the graph, the parameter services, ``/rosout``)
or the way the operating system does (the multicast groups joined).
"""

from __future__ import annotations

import asyncio
import itertools
import math
import os
import signal
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from ros2_support import (
    DEADLINE,
    SIM_NODE,
    next_where,
    require_rclpy,
    require_sim,
    sim_node_process,
    wait_for,
)

require_rclpy()
require_sim()

from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rcl_interfaces.msg import Log  # noqa: E402
from rcl_interfaces.srv import GetParameters  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402

from pyrobots_aio.cli import main  # noqa: E402

if TYPE_CHECKING:
    from collections.abc import Callable

    from ros2_support import PlainNode

DDS_MULTICAST = "0100FFEF"  # 239.255.0.1, DDS's discovery group, as /proc/net/igmp writes it
IGMP = Path("/proc/net/igmp")
ANSWER = 5.0  # seconds a parameter request waits for its answer before it is made again


def twist(v: float, w: float = 0.0) -> Twist:
    message = Twist()
    message.linear.x, message.angular.z = v, w
    return message


def stopped_node(process: subprocess.Popen[bytes]) -> tuple[int, str, str]:
    """SIGINT, then the exit code, standard output and standard error (the test is over)."""
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=DEADLINE)
    return process.returncode, out.decode(), err.decode()


# Commands that are not finite; one part finite (0.2 m/s forward, a turn of NaN) would move the
# robot if only the other were checked. Which comes first to the node is not known: a flood
# overwrites the oldest of the publisher's and the subscription's last 10 before they go out.
NAN_FLOOD = [(math.nan, 0.0), (0.2, math.nan)]
INF_FLOOD = [(math.inf, 0.0), (0.2, -math.inf), (-math.inf, 0.0)]
SETTLED = 1e-5  # m/s, rad/s: a stopped robot has rung down (its first ticks rock by 2 mm/s)
STILL = 1e-4  # the same, with margin: what a robot at rest never exceeds


def still(odom: Odometry, below: float = STILL) -> bool:
    return abs(odom.twist.twist.linear.x) < below and abs(odom.twist.twist.angular.z) < below


def flood(teleop: Any, commands: list[tuple[float, float]], count: int) -> None:
    """Publish ``count`` commands, cycling through ``commands``, as fast as rclpy sends them."""
    for v, w in itertools.islice(itertools.cycle(commands), count):
        teleop.publish(twist(v, w))


@pytest.mark.asyncio
async def test_ros_args_remap_set_use_sim_time_and_a_nan_flood_is_one_burst_on_rosout(
    plain: Callable[..., PlainNode],
) -> None:
    tool = plain("citizen_tool")
    rosout = tool.inbox("/rosout", Log, 100)
    clock = tool.inbox("/clock", Clock)
    odometry = tool.inbox("/odom", Odometry)
    teleop, matched = tool.publisher("/teleop_cmd", Twist)
    ros_args = ("-r", "__node:=citizen", "-r", "cmd_vel:=/teleop_cmd", "-p", "use_sim_time:=true")

    def from_citizen(word: str) -> Callable[[Log], bool]:
        return lambda m: m.name == "citizen" and word in m.msg

    with sim_node_process("--ros-args", *ros_args) as process:
        async with asyncio.timeout(DEADLINE):
            await matched.wait()  # cmd_vel remapped: sim-node listens on /teleop_cmd
            assert (await clock.get()).clock.sec < 1000  # use_sim_time: stamps are simulated
            served = ["rate", "cmd_timeout", "stall_timeout", "profile"]
            assert await parameters(tool, "/citizen", served) == [1.0, 0.5, 1.5, "standard"]
            assert await parameters(tool, "/citizen", ["use_sim_time"]) == [True]
            while (await odometry.get()).twist.twist.linear.x < 0.1:  # off it goes, as teleop
                teleop.publish(twist(0.2))
            flood(teleop, NAN_FLOOD, 2000)
            bursts = [
                (
                    await next_where(rosout, from_citizen("refused")),
                    await next_where(rosout, from_citizen("burst")),
                )
            ]
            stopped = await next_where(odometry, lambda o: still(o, SETTLED))
            flood(teleop, INF_FLOOD, 2000)  # a quiet second after the first: a burst again
            bursts.append(
                (
                    await next_where(rosout, from_citizen("refused")),
                    await next_where(rosout, from_citizen("burst")),
                )
            )
            # The odometry since the robot stopped: still through the second flood (what the
            # node published up to the second burst's end, which came a second after it).
            seen = [stopped]
            while not odometry.empty():
                seen.append(odometry.get_nowait())
            end = seen[-1].header.stamp.sec + 1
            while seen[-1].header.stamp.sec < end:
                seen.append(await odometry.get())
        code, out, err = stopped_node(process)
    for (first, over), commands in zip(bursts, (NAN_FLOOD, INF_FLOOD), strict=True):
        assert (first.level, over.level) == (Log.WARN, Log.WARN)
        assert first.msg in {
            f"/teleop_cmd: refused a command that is not finite ({v!r}, {w!r}): stopped; "
            "counting the refusals until 1 s pass without one"
            for v, w in commands
        }
        assert over.msg.startswith("/teleop_cmd: the burst is over: ")
        refused = int(over.msg.split(": ")[2].split()[0])
        assert 1 <= refused <= 2000
    assert [not still(o) for o in seen] == [False] * len(seen)  # the wheels stayed still
    x, y = stopped.pose.pose.position.x, stopped.pose.pose.position.y
    assert x > 0.0
    moved = [(o.pose.pose.position.x - x, o.pose.pose.position.y - y) for o in seen]
    assert moved == [pytest.approx((0.0, 0.0), abs=1e-4)] * len(seen)
    assert (code, out.splitlines()[-1]) == (0, "sim-node /citizen stopped")
    assert "Traceback" not in err
    assert err.count("refused a command that is not finite") == 2


async def parameters(tool: PlainNode, node: str, names: list[str]) -> list[Any]:
    """The values of ``node``'s parameters ``names``, as ``ros2 param get`` reads them.

    A DDS server drops a response to a client it has not matched yet (see
    `ros2_support.meet`): a call not answered within ANSWER seconds is made again.
    """
    client = tool.node.create_client(GetParameters, f"{node}/get_parameters")
    await wait_for(client.service_is_ready)
    while True:
        answered = answer(tool, client.call_async(GetParameters.Request(names=names)))
        try:
            async with asyncio.timeout(ANSWER):
                response = await answered
        except TimeoutError:
            continue
        fields = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value"}
        return [getattr(value, fields[value.type]) for value in response.values]


def answer(tool: PlainNode, call: Any) -> asyncio.Future[Any]:
    """A future of the test's loop settled with the rclpy future ``call``'s result."""
    answered: asyncio.Future[Any] = asyncio.get_running_loop().create_future()

    def settle(result: Any) -> None:
        if not answered.done():  # (a call given up on is not answered)
            answered.set_result(result)

    call.add_done_callback(lambda done: tool.to_loop(settle, done.result()))
    return answered


def test_bad_ros_args_are_refused_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sim-node", "--ros-args", "--bogus"]) == 1
    assert capsys.readouterr().err.endswith(
        "pyrobots-aio: error: unknown ROS arguments ['--bogus'] in --ros-args --bogus\n"
    )


def test_a_parameter_that_is_an_option_is_refused_naming_the_option() -> None:
    done = subprocess.run(
        [*SIM_NODE, "--ros-args", "-p", "rate:=4.0"],
        capture_output=True,
        timeout=DEADLINE,
        check=False,
    )
    assert done.returncode == 1
    assert done.stderr.decode().endswith(
        "pyrobots-aio: error: the parameter 'rate' is sim-node's --rate option: give --rate "
        "VALUE instead of -p rate:=... in --ros-args\n"
    )


def joined_beyond_loopback() -> list[str]:
    """The interfaces other than ``lo`` where some socket joined DDS's multicast group."""
    joined, device = [], ""
    for line in IGMP.read_text().splitlines()[1:]:
        if not line.startswith("\t"):
            device = line.split()[1]
        elif line.split()[0] == DDS_MULTICAST and device != "lo":
            joined.append(device)
    return joined


@pytest.mark.skipif(not IGMP.exists(), reason="no /proc/net/igmp to read multicast groups from")
def test_discovery_stays_on_this_machine_unless_the_environment_says_otherwise() -> None:
    """What this proves: with the range unset, sim-node joins no multicast group off loopback.

    /proc/net/igmp is the network namespace's, not the process's: another
    process of the machine joining 239.255.0.1 meanwhile would show there too,
    so the check is that the count does not grow while ours runs, and the
    control (``SUBNET`` set by the user) shows that the check sees a join.
    """
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in {"ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOCALHOST_ONLY"}
    }
    before = joined_beyond_loopback()
    with sim_node_process("--name", "unset_range", env=env):
        assert joined_beyond_loopback() == before
    with sim_node_process(
        "--name", "subnet_range", env={**env, "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}
    ):
        joined = joined_beyond_loopback()
    assert len(joined) > len(before)
