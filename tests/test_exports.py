"""The public namespace: complete __all__ lists, every name importable (httpx style)."""

from __future__ import annotations

import importlib

import pytest

import pyrobots_aio

PUBLIC = [
    "pyrobots_aio",
    "pyrobots_aio.actions",
    "pyrobots_aio.events",
    "pyrobots_aio.loops",
    "pyrobots_aio.motion",
    "pyrobots_aio.poses",
    "pyrobots_aio.resources",
    "pyrobots_aio.robot",
    "pyrobots_aio.ros2",
    "pyrobots_aio.sim",
    "pyrobots_aio.state",
    "pyrobots_aio.supervision",
    "pyrobots_aio.telemetry",
    "pyrobots_aio.testing",
    "pyrobots_aio.testing.explore",
]


@pytest.mark.parametrize("name", PUBLIC)
def test_all_is_complete_and_importable(name: str) -> None:
    module = importlib.import_module(name)
    exported = module.__all__  # its order is ruff's RUF022 (isort-style), checked by lint
    assert len(set(exported)) == len(exported)
    for item in exported:
        assert hasattr(module, item), f"{name}.{item} is in __all__ but missing"


def test_the_design_names_are_importable_from_the_package() -> None:
    names = {
        "Robot", "GenericRobot", "action", "ActionHandle", "Outcome", "ActionCancelled",
        "ActionInterrupted", "ActionSkipped", "TooManyActions", "PyRobotsError", "Resource",
        "CompoundResource", "lock", "Pose", "FrameProvider", "InvalidPoseError",
        "UnknownFrameError", "EventMonitor", "StateStore", "ActionInfo", "DriveBase",
        "retry", "exponential", "timeout", "HealthMonitor", "StateMachine",
        "ResourceDeadlockError",
    }  # fmt: skip
    assert names <= set(pyrobots_aio.__all__)
    assert pyrobots_aio.ActionCancelled is __import__("asyncio").CancelledError


def test_every_public_name_has_a_docstring() -> None:
    for name in pyrobots_aio.__all__:
        obj = getattr(pyrobots_aio, name)
        if callable(obj) and name != "ActionCancelled":
            assert obj.__doc__, f"pyrobots_aio.{name} has no docstring"
