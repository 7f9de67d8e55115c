"""The ROS 2 tests' own rule: a missing part skips with its reason, or fails where none may skip.

``nox -s ros2`` sets ``PYROBOTS_AIO_REQUIRE_ROS2=1``: there a missing rclpy, simulator or built
interface package (tf2_msgs, irobot_create_msgs) fails the tests that need it, instead of
skipping them quietly.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from ros2_support import REQUIRE, require_interfaces

MISSING = "no_such_msgs"


def test_a_missing_package_skips_the_caller_with_its_reason(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(REQUIRE, raising=False)
    with pytest.raises(pytest.skip.Exception) as caught:
        require_interfaces(MISSING)
    assert str(caught.value) == f"it is not built: pyrobots-aio ros2 interfaces build {MISSING}"


def test_a_missing_package_fails_the_caller_where_ros2_is_required(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv(REQUIRE, "1")
    with pytest.raises(pytest.fail.Exception) as caught:
        require_interfaces(MISSING)
    assert str(caught.value) == (
        f"PYROBOTS_AIO_REQUIRE_ROS2=1 but {MISSING} cannot be imported (No module named "
        f"'{MISSING}'): it is not built: pyrobots-aio ros2 interfaces build {MISSING}"
    )


def test_no_ros2_test_skips_for_a_missing_module_on_its_own() -> None:
    """Each goes through ``ros2_support.require``, which fails under the variable."""
    own_skip = re.compile(r"pytest\.importorskip\(")
    found = [
        path.name
        for path in sorted(Path(__file__).parent.glob("test_*.py"))
        if own_skip.search(path.read_text())
    ]
    assert found == []
