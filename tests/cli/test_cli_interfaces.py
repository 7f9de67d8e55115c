"""``pyrobots-aio ros2 interfaces build``: its arguments (the builds: tests/ros2)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from pyrobots_aio import InterfaceBuildError
from pyrobots_aio.cli import main
from pyrobots_aio.ros2 import build_interfaces, interface_packages

if TYPE_CHECKING:
    from pathlib import Path


def test_an_unknown_package_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ros2", "interfaces", "build", "tf2_msgs", "nav2_msgs"]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "pyrobots-aio ros2 interfaces build: error: argument PACKAGE: unknown interface "
        "package 'nav2_msgs'; choose from irobot_create_msgs, tf2_msgs"
    )


def test_jobs_must_be_positive(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ros2", "interfaces", "build", "--jobs", "0"]) == 2
    assert capsys.readouterr().err.splitlines()[-1] == (
        "pyrobots-aio ros2 interfaces build: error: argument -j/--jobs: "
        "expected a positive integer, got '0'"
    )


def test_the_api_refuses_what_the_command_refuses(tmp_path: Path) -> None:
    with pytest.raises(InterfaceBuildError) as caught:
        build_interfaces(["nav2_msgs"], prefix=tmp_path)
    assert str(caught.value) == (
        "unknown interface packages ['nav2_msgs']; pyrobots_aio builds "
        "['irobot_create_msgs', 'tf2_msgs']"
    )
    with pytest.raises(ValueError, match=r"^jobs must be at least 1, got 0$"):
        build_interfaces(prefix=tmp_path, jobs=0)
    assert not (tmp_path / "share").exists()


def test_each_package_carried_is_marked_as_pyrobots_aio_s_copy() -> None:
    """An installed package.xml without the marker is another install's, which wins."""
    from pyrobots_aio.ros2 import _interfaces

    for package in interface_packages():
        manifest = _interfaces.DEFINITIONS / package / "package.xml"
        assert _interfaces.MARKER in manifest.read_text()
