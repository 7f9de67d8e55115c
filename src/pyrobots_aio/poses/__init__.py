"""Poses and frames: `Pose` values, the `PoseManager` (``robot.poses``), frame providers.

A `Pose` is a frozen position + x-first quaternion in a named frame. The
`PoseManager` reads the raw formats users write (``"base_link"``,
``(x, y, z)``, dicts, matrices, ...), and expresses poses in other frames
through `FrameProvider`s: a `FrameTree` of static or updated transforms, the
simulator's provider, anything with ``get_transform(frame)`` and
``frames()``. This layer uses only numpy and transforms3d.
"""

from ._frames import FrameProvider as FrameProvider
from ._frames import FrameTree as FrameTree
from ._manager import PoseManager as PoseManager
from ._math import Matrix as Matrix
from ._math import Pose2D as Pose2D
from ._parse import PoseLike as PoseLike
from ._pose import Pose as Pose

__all__ = [
    "FrameProvider",
    "FrameTree",
    "Matrix",
    "Pose",
    "Pose2D",
    "PoseLike",
    "PoseManager",
]
