"""`Pose`: a position and an orientation in a named frame, as a frozen value.

One quaternion convention inside: the fields are ``qx qy qz qw`` (x-first, as
in ROS messages). transforms3d and MuJoCo are w-first; conversions happen only
at the named boundaries (`Pose.quat_wxyz`, `Pose.from_wxyz`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
import transforms3d.euler as t3d_euler
import transforms3d.quaternions as t3d_quat
from numpy.typing import NDArray

from .._exceptions import InvalidPoseError
from ._math import UNIT_TOLERANCE, Matrix, finite_float, finite_floats, rigid_matrix

Vector: TypeAlias = NDArray[np.float64]
"""A 1-D float64 array (a position or a quaternion)."""

_NUMERIC_FIELDS = ("x", "y", "z", "qx", "qy", "qz", "qw")
# Norms this close to 1 are left alone, so rebuilding a pose from its own fields
# gives an equal pose (dividing by a norm of 1 - 1e-16 would move the last bit).
_UNIT_EXACT = 1e-12


def frame_name(value: object, what: str = "frame") -> str:
    """Return ``value`` if it is a non-empty string, else raise `InvalidPoseError`."""
    if isinstance(value, str) and value:
        return value
    msg = f"{what} must be a non-empty string, got {value!r}"
    raise InvalidPoseError(msg)


@dataclass(frozen=True, slots=True)
class Pose:
    """A position and orientation in a named frame; immutable and validated.

    Fields are floats except ``frame``. The orientation is the unit quaternion
    ``(qx, qy, qz, qw)`` (x-first; default: the identity), and ``frame`` the
    name of the frame the pose is expressed in (default ``"map"``).

    Validation at construction: every number must be a finite real (a bool is
    not one; ints are stored as floats); the frame a non-empty string; the
    quaternion non-zero with a norm within 1e-3 of 1 (``UNIT_TOLERANCE``). A
    near-unit quaternion (e.g. typed as ``0.7071``) is normalised (unless
    already within 1e-12 of unit, so rebuilding a pose gives an equal one); anything
    further from unit is rejected rather than silently rescaled, since it is
    almost always a mistake (wrong order, Euler angles in quaternion slots).
    ``q`` and ``-q`` are the same rotation but different field values;
    compare rotations with `isclose`.

    Raises:
        InvalidPoseError: A field is not a finite number, the quaternion is
            zero or not unit, or the frame is not a non-empty string.

    Examples:
        >>> p = Pose(1.0, 2.0, 0.0, frame="odom")
        >>> p.position().tolist(), p.quat_wxyz().tolist()
        ([1.0, 2.0, 0.0], [1.0, 0.0, 0.0, 0.0])
        >>> Pose(qz=0.7071, qw=0.7071).qz
        0.7071067811865476
    """

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    qx: float = 0.0
    qy: float = 0.0
    qz: float = 0.0
    qw: float = 1.0
    frame: str = "map"

    def __post_init__(self) -> None:
        for name in _NUMERIC_FIELDS:
            object.__setattr__(self, name, finite_float(name, getattr(self, name)))
        frame_name(self.frame)
        quat = (self.qx, self.qy, self.qz, self.qw)
        norm = math.sqrt(sum(c * c for c in quat))
        if norm == 0.0:
            msg = (
                f"quaternion (qx, qy, qz, qw) = {quat} is zero; "
                "expected a unit quaternion, e.g. the identity (0, 0, 0, 1)"
            )
            raise InvalidPoseError(msg)
        if abs(norm - 1.0) > UNIT_TOLERANCE:
            msg = (
                f"quaternion (qx, qy, qz, qw) = {quat} has norm {norm:.6g}; "
                f"expected a unit quaternion (norm within {UNIT_TOLERANCE} of 1)"
            )
            raise InvalidPoseError(msg)
        if abs(norm - 1.0) > _UNIT_EXACT:
            for name, component in zip(("qx", "qy", "qz", "qw"), quat, strict=True):
                object.__setattr__(self, name, component / norm)

    @classmethod
    def from_matrix(cls, matrix: Matrix | Sequence[Sequence[float]], frame: str = "map") -> Pose:
        """Build a pose from a 4x4 rigid transform (numpy array or nested sequence).

        The matrix maps points of the pose's own frame into ``frame``: its last
        column is the position, its upper-left 3x3 block the rotation.

        Raises:
            InvalidPoseError: The matrix is not 4x4, holds non-finite or
                non-numeric entries, or is not rigid (see `UNIT_TOLERANCE`).

        Examples:
            >>> import numpy as np
            >>> m = np.eye(4)
            >>> m[:3, 3] = (1.0, 2.0, 3.0)
            >>> Pose.from_matrix(m, "odom")
            Pose(x=1.0, y=2.0, z=3.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='odom')
        """
        rigid = rigid_matrix(matrix)
        w, qx, qy, qz = (float(c) for c in t3d_quat.mat2quat(rigid[:3, :3]))
        x, y, z = (float(c) for c in rigid[:3, 3])
        return cls(x, y, z, qx, qy, qz, w, frame)

    @classmethod
    def from_euler(  # noqa: PLR0917  # mirrors the (x, y, z, rx, ry, rz, frame) format
        cls,
        x: float,
        y: float,
        z: float,
        rx: float,
        ry: float,
        rz: float,
        frame: str = "map",
    ) -> Pose:
        """Build a pose from a position and static-axes ``sxyz`` Euler angles (radians).

        ``sxyz``: rotate by ``rx`` about the fixed x axis, then ``ry`` about the
        fixed y axis, then ``rz`` about the fixed z axis (roll, pitch, yaw).

        Examples:
            >>> p = Pose.from_euler(0, 0, 0, 0, 0, math.pi / 2)
            >>> [round(c, 6) for c in p.quat_xyzw().tolist()]
            [0.0, 0.0, 0.707107, 0.707107]
        """
        angles = finite_floats(("rx", "ry", "rz"), (rx, ry, rz), "Euler angles")
        w, qx, qy, qz = (float(c) for c in t3d_euler.euler2quat(*angles, axes="sxyz"))
        return cls(x, y, z, qx, qy, qz, w, frame)

    @classmethod
    def from_wxyz(
        cls,
        position: Sequence[float] | Vector,
        quat_wxyz: Sequence[float] | Vector,
        frame: str = "map",
    ) -> Pose:
        """Build a pose from a position and a w-first quaternion (MuJoCo, transforms3d).

        Examples:
            >>> Pose.from_wxyz([1, 0, 0], [1, 0, 0, 0]).x
            1.0
        """
        x, y, z = finite_floats(("x", "y", "z"), position, "position")
        w, qx, qy, qz = finite_floats(("qw", "qx", "qy", "qz"), quat_wxyz, "quat_wxyz")
        return cls(x, y, z, qx, qy, qz, w, frame)

    def position(self) -> Vector:
        """Return ``[x, y, z]`` as a new float64 array."""
        return np.array([self.x, self.y, self.z], dtype=np.float64)

    def quat_xyzw(self) -> Vector:
        """Return the quaternion x-first, ``[qx, qy, qz, qw]`` (ROS order)."""
        return np.array([self.qx, self.qy, self.qz, self.qw], dtype=np.float64)

    def quat_wxyz(self) -> Vector:
        """Return the quaternion w-first, ``[qw, qx, qy, qz]`` (transforms3d, MuJoCo order)."""
        return np.array([self.qw, self.qx, self.qy, self.qz], dtype=np.float64)

    def matrix(self) -> Matrix:
        """Return the 4x4 transform that maps points of this pose's frame into ``frame``."""
        matrix = np.eye(4)
        matrix[:3, :3] = t3d_quat.quat2mat(self.quat_wxyz())
        matrix[:3, 3] = (self.x, self.y, self.z)
        return matrix

    def euler(self) -> tuple[float, float, float]:
        """Return the orientation as static-axes ``sxyz`` Euler angles ``(rx, ry, rz)``.

        ``ry`` is in [-π/2, π/2], ``rx`` and ``rz`` in [-π, π].
        """
        rx, ry, rz = (float(a) for a in t3d_euler.quat2euler(self.quat_wxyz(), axes="sxyz"))
        return (rx, ry, rz)

    def isclose(self, other: Pose, *, atol: float = 1e-9) -> bool:
        """Whether ``other`` is the same frame, position and rotation within ``atol``.

        Positions and quaternion components are compared component-wise;
        ``q`` and ``-q`` count as the same rotation.

        Examples:
            >>> Pose(qw=1.0).isclose(Pose(qw=-1.0))
            True
        """
        if self.frame != other.frame:
            return False
        if not np.allclose(self.position(), other.position(), rtol=0.0, atol=atol):
            return False
        mine, theirs = self.quat_xyzw(), other.quat_xyzw()
        return bool(
            np.allclose(mine, theirs, rtol=0.0, atol=atol)
            or np.allclose(mine, -theirs, rtol=0.0, atol=atol)
        )
