"""The simulator's frames (``odom``, ``base_link``, sensors, ``dock``) for ``robot.poses``."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Collection

    import numpy as np
    from numpy.typing import NDArray

    from ._world import SimWorld


class WorldFrames:
    """A `FrameProvider` reading the frames of a `SimWorld` as they are now.

    Nothing is copied per tick: each lookup asks the physics for the current
    transform, so a pose is always expressed with the latest robot position.
    """

    def __init__(self, world: SimWorld) -> None:
        self._world = world

    def get_transform(self, frame: str) -> NDArray[np.float64]:
        """The 4x4 transform from ``frame`` to ``map``."""
        return self._world.frame_transform(frame)

    def get_planar(self, frame: str) -> tuple[float, float, float]:
        """``(x, y, yaw)`` of ``frame`` in ``map`` (`PoseManager.planar`), read directly."""
        return self._world.frame_planar(frame)

    def frames(self) -> Collection[str]:
        """Every frame the simulator places."""
        return self._world.frame_names

    def __repr__(self) -> str:
        return f"<WorldFrames {sorted(self.frames())}>"
