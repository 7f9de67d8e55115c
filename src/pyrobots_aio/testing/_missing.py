"""Stand-ins registered when pytest-asyncio is missing or too old: each says what to install."""

from __future__ import annotations

from typing import TYPE_CHECKING, NoReturn

import pytest

if TYPE_CHECKING:
    from collections.abc import Callable

PROBLEM = "pytest-asyncio>=1.4 is needed"
"""Set by the plugin to the reason and the fix."""


def _stand_in(name: str) -> Callable[[], NoReturn]:
    @pytest.fixture(name=name)
    def unavailable() -> NoReturn:
        pytest.fail(f"fixture {name!r}: {PROBLEM}", pytrace=False)

    return unavailable


robot = _stand_in("robot")
sim_robot = _stand_in("sim_robot")
robot_events = _stand_in("robot_events")
no_leaked_tasks = _stand_in("no_leaked_tasks")
module_robot = _stand_in("module_robot")
module_sim_robot = _stand_in("module_sim_robot")
module_robot_events = _stand_in("module_robot_events")
session_robot = _stand_in("session_robot")
session_sim_robot = _stand_in("session_sim_robot")
session_robot_events = _stand_in("session_robot_events")


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A test marked ``virtual_time`` cannot run on the virtual-time loop: say why."""
    if item.get_closest_marker("virtual_time"):
        pytest.fail(f"marker 'virtual_time': {PROBLEM}", pytrace=False)
