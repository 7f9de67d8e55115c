"""``pyrobots-aio ros2 interfaces build``: tf2_msgs and irobot_create_msgs from their definitions.

``nox -s ros2`` builds them once before the tests (the ``ros2-build`` extra);
here they are built if they are not yet. The packages built are only ever
imported by subprocesses: the rebuild below replaces files of this prefix.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from ros2_support import DEADLINE, REQUIRE, require_rclpy

from pyrobots_aio import InterfaceBuildError
from pyrobots_aio.ros2 import InterfaceOutcome, _interfaces, build_interfaces, interface_packages
from pyrobots_aio.ros2._interfaces import missing_tools

if TYPE_CHECKING:
    from collections.abc import Iterator

require_rclpy()
if missing_tools() and os.environ.get(REQUIRE) != "1":
    pytest.skip(
        f"cannot build ROS 2 interfaces here: {'; '.join(missing_tools())}",
        allow_module_level=True,
    )

pytestmark = pytest.mark.timeout(DEADLINE * 15)  # a first build takes minutes on 2 cores

PREFIX = Path(sys.prefix).resolve()
NO_MAKE = "no make, which cmake's Unix Makefiles generator runs (apt-get install make)"
BUILD = [sys.executable, "-m", "pyrobots_aio.cli", "ros2", "interfaces", "build"]
STATE = PREFIX / "share" / "pyrobots_aio" / "interfaces"
TOOLS = [
    "ament_cmake", "ament_cmake_include_directories", "ament_cmake_ros_core", "rosidl_cmake",
    "rosidl_generator_c", "rosidl_generator_py", "rosidl_generator_type_description",
    "rosidl_typesupport_c", "rosidl_typesupport_fastrtps_c",
    "rosidl_typesupport_introspection_c", "builtin_interfaces", "geometry_msgs",
]  # fmt: skip
"""What an empty prefix lacks to build tf2_msgs (the toolchain, then its dependencies)."""

# The real type hashes (RIHS01) of upstream's definitions:
# - tf2_msgs: `ros2 topic info --verbose /robot1/tf` on a ROS 2 Jazzy system (amcl and
#   robot_state_publisher publishing), in a public field report; TF2Error: the golden hashes of a
#   public ROS 2 client library's tests, which give the same TFMessage hash.
# - irobot_create_msgs (2.1.0, iRobotEducation/irobot_create_msgs): no real system's hashes are
#   published; these were computed by rosbags 0.11 (an independent, pure-Python implementation of
#   the hashing standard, which gives the two tf2_msgs hashes above) from upstream's own .msg
#   files and its ROS 2 Jazzy store for std_msgs. The Create 3's actions likewise, from upstream's
#   .action files: rosbags hashes messages only, so each action's parts were registered as the
#   messages ROS 2's type-description standard (REP 2011) makes of an action (X_Goal, X_Result,
#   X_Feedback, X_SendGoal and X_GetResult with their _Request, _Response and _Event,
#   X_FeedbackMessage, and X itself), on rosbags' Jazzy store with one correction:
#   service_msgs/ServiceEventInfo's client_gid as uint8[16] (ROS 2 reads a .msg `char` as uint8;
#   rosbags keeps char), which gives the real Jazzy wheel's ServiceEventInfo hash.
UPSTREAM_HASHES = {
    "tf2_msgs/msg/TFMessage": (
        "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"
    ),
    "tf2_msgs/msg/TF2Error": (
        "RIHS01_db2485e7d6a0ec75bf087e058ee45df682acc3a621ca7780503d10aac141809a"
    ),
    "irobot_create_msgs/msg/HazardDetectionVector": (
        "RIHS01_90913822b0a9155a64b12352ba73b2ca9248d73874ebf7700ed277b2dca57edd"
    ),
    "irobot_create_msgs/msg/HazardDetection": (
        "RIHS01_ca2fe36a5bcf9c309e62060716d6ea354ee477686dac2ec089f7c91f2f30d8e6"
    ),
    "irobot_create_msgs/msg/IrIntensityVector": (
        "RIHS01_ab28b9f9a113268373d08ab94fa53a9cf8953d83843a11b8dd39ea693c99ccba"
    ),
    "irobot_create_msgs/msg/DockStatus": (
        "RIHS01_34ecea6599a01ad532400408b71cb54be1c1617b50ed529090abc1c70b4c9fa1"
    ),
    "irobot_create_msgs/action/Undock": (
        "RIHS01_49d6663bcb9cb87eec55425d44022f96497837ce5b57bcb90d330f998f82fc94"
    ),
    "irobot_create_msgs/action/Dock": (
        "RIHS01_5ef2f23a85c099203133e1d29e3ff6e65ce4a836b30b69fb91ec9a9e7641854f"
    ),
    "irobot_create_msgs/action/DriveDistance": (
        "RIHS01_7b9946318423b4f7f1ebc0a50ae7f0e0113c3a459502edfa583869a787adf520"
    ),
    "irobot_create_msgs/action/RotateAngle": (
        "RIHS01_f7c808bf7a76b2269749cc8885d72a2da085fa89f6620d98e1bedc78ea9515a9"
    ),
    "irobot_create_msgs/action/NavigateToPosition": (
        "RIHS01_d9c3b82a52c695fef55a80ff467fef80d1cfd837df0f213e11c37e50116b8ef7"
    ),
}


@pytest.fixture(scope="module", autouse=True)
def built() -> None:
    """Both packages built into this environment (a no-op after ``nox -s ros2``'s build)."""
    outcomes = build_interfaces()
    assert {(o.package, o.where) for o in outcomes} == {
        ("irobot_create_msgs", PREFIX),
        ("tf2_msgs", PREFIX),
    }


def run_build(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """Run the command (in ``env``, else this one's) to its end."""
    return subprocess.run(
        [*BUILD, *args], capture_output=True, text=True, timeout=DEADLINE * 10, env=env, check=False
    )


def bare_environment(path: Path, **variables: str) -> dict[str, str]:
    """This environment with ``PATH`` only ``path``, no ``CC`` or ``CXX``, and ``variables``."""
    dropped = {"CC", "CXX", "AMENT_PREFIX_PATH", "CMAKE_GENERATOR"}
    kept = {k: v for k, v in os.environ.items() if k not in dropped}
    return {**kept, "PATH": str(path), **variables}


def compilers_only(folder: Path) -> Path:
    """``folder``, holding this machine's compilers and cmake and no make or ninja."""
    folder.mkdir()
    for program in ("cc", "c++", "cmake"):
        found = shutil.which(
            program, path=os.pathsep.join([str(PREFIX / "bin"), os.environ["PATH"]])
        )
        assert found is not None, f"the test needs {program}"
        (folder / program).symlink_to(found)
    return folder


@pytest.fixture
def stale_tf2_msgs() -> Iterator[None]:
    """tf2_msgs' stamp says it is stale (a build would run), and is put back after."""
    stamp = STATE / "tf2_msgs.stamp"
    saved = stamp.read_text()
    stamp.write_text("stale")
    yield
    stamp.write_text(saved)


def test_the_project_carries_both_packages() -> None:
    assert interface_packages() == ("irobot_create_msgs", "tf2_msgs")


def test_a_second_build_is_a_no_op() -> None:
    installed = PREFIX / "share" / "irobot_create_msgs" / "package.xml"
    before = installed.stat().st_mtime_ns
    done = run_build()
    assert done.returncode == 0, done.stderr
    assert done.stdout == (
        f"irobot_create_msgs: up to date in {PREFIX}\ntf2_msgs: up to date in {PREFIX}\n"
    )
    assert installed.stat().st_mtime_ns == before


def test_two_builds_at_once_both_succeed_and_build_once() -> None:
    (STATE / "tf2_msgs.stamp").unlink()  # tf2_msgs is stale: rebuilt (the smaller package)
    first = subprocess.Popen(
        [*BUILD, "tf2_msgs"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert first.stderr is not None
        said = ""
        for line in iter(first.stderr.readline, ""):
            said += line
            if "building tf2_msgs into" in line:  # it holds the lock now
                break
        assert "building tf2_msgs into" in said, said
        second = run_build("tf2_msgs")
        out, err = first.communicate(timeout=DEADLINE * 10)
    finally:
        if first.poll() is None:
            first.kill()
            first.communicate()
    assert first.returncode == 0, err
    assert out.startswith(f"tf2_msgs: built into {PREFIX} in ")
    assert second.returncode == 0, second.stderr
    assert "another build of the interfaces is running" in second.stderr
    assert second.stdout == f"tf2_msgs: up to date in {PREFIX}\n"


def test_missing_tools_are_named_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))  # no cmake, no compilers
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.delenv("CXX", raising=False)
    monkeypatch.delenv("CMAKE_GENERATOR", raising=False)
    with pytest.raises(InterfaceBuildError) as caught:
        build_interfaces(["tf2_msgs"], prefix=tmp_path)  # an empty prefix: no build tools
    assert str(caught.value) == (
        f"cannot build the ROS 2 interfaces tf2_msgs: no cmake (pip install cmake); {NO_MAKE}; "
        "no C compiler (apt-get install gcc); no C++ compiler (apt-get install g++); "
        f"no ROS 2 build tools {TOOLS} (pip install 'pyrobots-aio[ros2-build]')"
    )


@pytest.mark.usefixtures("stale_tf2_msgs")
def test_the_command_names_a_missing_compiler_and_builds_nothing(tmp_path: Path) -> None:
    done = run_build("tf2_msgs", env=bare_environment(tmp_path, CXX="no-such-c++"))
    cmake = "" if (PREFIX / "bin" / "cmake").exists() else "no cmake (pip install cmake); "
    assert done.returncode == 1
    assert done.stderr.splitlines()[-1] == (
        f"pyrobots-aio: error: cannot build the ROS 2 interfaces tf2_msgs: {cmake}{NO_MAKE}; "
        "no C compiler (apt-get install gcc); "
        "CXX='no-such-c++' is not a program (apt-get install g++)"
    )
    assert done.stdout == ""


@pytest.mark.usefixtures("stale_tf2_msgs")
def test_the_command_names_a_missing_make_in_one_line_and_builds_nothing(tmp_path: Path) -> None:
    """Not cmake's configure step failing with its log: the one program missing, named."""
    done = run_build("tf2_msgs", env=bare_environment(compilers_only(tmp_path / "bin")))
    assert done.returncode == 1
    assert done.stderr.splitlines()[-1] == (
        f"pyrobots-aio: error: cannot build the ROS 2 interfaces tf2_msgs: {NO_MAKE}"
    )
    assert done.stdout == ""


def test_a_missing_ninja_is_named_under_the_ninja_generator(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PATH", str(compilers_only(tmp_path / "bin")))
    monkeypatch.setenv("CMAKE_GENERATOR", "Ninja")
    assert missing_tools(["tf2_msgs"], prefix=tmp_path) == [
        "no ninja, which cmake's Ninja generator runs (pip install ninja)",
        f"no ROS 2 build tools {TOOLS} (pip install 'pyrobots-aio[ros2-build]')",
    ]


def test_missing_python_headers_are_named_with_the_package_that_has_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_interfaces.sysconfig, "get_paths", lambda: {"include": str(tmp_path)})
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    assert missing_tools(["tf2_msgs"]) == [
        f"no Python headers (no {tmp_path / 'Python.h'}: apt-get install python{version}-dev)"
    ]


def test_a_sourced_ros2_s_own_package_wins(tmp_path: Path) -> None:
    sourced = tmp_path / "opt" / "ros"
    (sourced / "share" / "tf2_msgs").mkdir(parents=True)
    (sourced / "share" / "tf2_msgs" / "package.xml").write_text("<package format='3'/>")
    stamp = (STATE / "tf2_msgs.stamp").stat().st_mtime_ns
    done = run_build("tf2_msgs", env=bare_environment(tmp_path, AMENT_PREFIX_PATH=str(sourced)))
    assert done.returncode == 0, done.stderr  # though there are no compilers
    assert done.stdout == f"tf2_msgs: provided by {sourced}; built nothing\n"
    assert (STATE / "tf2_msgs.stamp").stat().st_mtime_ns == stamp


def test_another_install_in_the_prefix_is_left_alone(tmp_path: Path) -> None:
    (tmp_path / "share" / "tf2_msgs").mkdir(parents=True)
    (tmp_path / "share" / "tf2_msgs" / "package.xml").write_text("<package format='3'/>")
    (outcome,) = build_interfaces(["tf2_msgs"], prefix=tmp_path)
    assert (outcome.outcome, outcome.where) == (InterfaceOutcome.PROVIDED, tmp_path.resolve())


def test_the_generated_type_hashes_are_upstreams() -> None:
    for name, expected in UPSTREAM_HASHES.items():
        package, kind, interface = name.split("/")
        description = PREFIX / "share" / package / kind / f"{interface}.json"
        (first, *_) = json.loads(description.read_text())["type_hashes"]
        assert first == {"type_name": name, "hash_string": expected}


PUBLISHER = """
import sys

import rclpy
from geometry_msgs.msg import TransformStamped
from irobot_create_msgs.msg import HazardDetection, HazardDetectionVector
from rclpy.qos import DurabilityPolicy, QoSProfile
from tf2_msgs.msg import TFMessage

rclpy.init()
node = rclpy.create_node("interfaces_publisher")
latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
edge = TransformStamped(child_frame_id="base_link")
edge.header.frame_id = "odom"
edge.transform.translation.x = 1.5
edge.transform.rotation.w = 1.0
bump = HazardDetection(type=HazardDetection.BUMP)
bump.header.frame_id = "bump_front_center"
cliff = HazardDetection(type=HazardDetection.CLIFF)
cliff.header.frame_id = "cliff_side_left"
node.create_publisher(TFMessage, "roundtrip_tf", latched).publish(TFMessage(transforms=[edge]))
node.create_publisher(HazardDetectionVector, "roundtrip_hazards", latched).publish(
    HazardDetectionVector(detections=[bump, cliff])
)
print("published", flush=True)
sys.stdin.read()  # until the test is done with it
"""

SUBSCRIBER = """
import json

import rclpy
from irobot_create_msgs.msg import HazardDetectionVector
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.task import Future
from tf2_msgs.msg import TFMessage

rclpy.init()
node = rclpy.create_node("interfaces_subscriber")
latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
got, done = {}, Future()


def keep(topic, fields):
    def received(message):
        got[topic] = fields(message)
        if len(got) == 2:
            done.set_result(True)

    return received


node.create_subscription(TFMessage, "roundtrip_tf", keep("roundtrip_tf", lambda m: [
    [t.header.frame_id, t.child_frame_id, t.transform.translation.x] for t in m.transforms
]), latched)
node.create_subscription(HazardDetectionVector, "roundtrip_hazards", keep(
    "roundtrip_hazards", lambda m: [[d.header.frame_id, d.type] for d in m.detections]
), latched)
rclpy.spin_until_future_complete(node, done, timeout_sec=DEADLINE)
hashes = {
    topic: sorted({str(i.topic_type_hash) for i in node.get_publishers_info_by_topic(topic)})
    for topic in got
}
print(json.dumps({"got": got, "hashes": hashes}))
"""


def test_a_tf_message_and_hazards_go_from_one_process_to_another() -> None:
    publisher = subprocess.Popen(
        [sys.executable, "-c", PUBLISHER],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert publisher.stdout is not None
        assert publisher.stdout.readline() == "published\n"
        script = SUBSCRIBER.replace("DEADLINE", repr(DEADLINE))
        subscriber = subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            timeout=DEADLINE * 2,
            check=False,
        )
    finally:
        publisher.communicate(timeout=DEADLINE)
    assert subscriber.returncode == 0, subscriber.stderr
    assert json.loads(subscriber.stdout) == {
        "got": {
            "roundtrip_tf": [["odom", "base_link", 1.5]],
            "roundtrip_hazards": [["bump_front_center", 1], ["cliff_side_left", 2]],
        },
        "hashes": {  # what the publisher's process announces on the wire
            "roundtrip_tf": [UPSTREAM_HASHES["tf2_msgs/msg/TFMessage"]],
            "roundtrip_hazards": [UPSTREAM_HASHES["irobot_create_msgs/msg/HazardDetectionVector"]],
        },
    }
