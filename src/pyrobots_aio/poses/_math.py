"""Numbers, angles, rigid matrices and polygons: the arithmetic under poses.

Everything here is pure (no frames, no providers). Rotations go through
transforms3d, whose quaternions are w-first; the functions that return a
quaternion to users say which order they use.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence
from typing import TypeAlias

import numpy as np
import transforms3d.euler as t3d_euler
from numpy.typing import NDArray

from .._core._numbers import as_float, finite, shown
from .._exceptions import InvalidPoseError

Matrix: TypeAlias = NDArray[np.float64]
"""A 4x4 homogeneous rigid transform (float64)."""

Pose2D: TypeAlias = tuple[float, float, float]
"""A planar pose ``(x, y, yaw)``, in metres and radians (a base's odometry, a robot on a map)."""

UNIT_TOLERANCE = 1e-3
"""How far from 1 a quaternion's norm, or ``R @ R.T`` from the identity, may be."""

EDGE_TOLERANCE = 1e-9
"""A point this close (in the polygon's units) to an edge is on that edge."""

TAU = 2.0 * math.pi
_LAST_ROW = (0.0, 0.0, 0.0, 1.0)


def show(value: object) -> str:
    """Return a one-line, bounded ``repr`` of ``value`` for error messages."""
    return f"array({shown(value.tolist())})" if isinstance(value, np.ndarray) else shown(value)


def is_number(value: object) -> bool:
    """Whether ``value`` is a real number a float can hold (or NaN, or infinite); not a bool."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    number: object = value  # typeshed's Real and int do not mix
    return not isinstance(number, int) or as_float(number) is not None


def finite_float(name: str, value: object) -> float:
    """Return ``value`` as a float, or raise `InvalidPoseError` naming ``name``."""
    return finite(name, value, must="a finite real number", error=InvalidPoseError)


def finite_floats(names: Sequence[str], values: object, what: str) -> list[float]:
    """Read exactly ``len(names)`` finite numbers from a sequence or 1-D array."""
    items = values.tolist() if isinstance(values, np.ndarray) else values
    if isinstance(items, str | bytes) or not isinstance(items, Sequence):
        msg = f"{what} must be a sequence of {len(names)} numbers, got {show(values)}"
        raise InvalidPoseError(msg)
    if len(items) != len(names):
        msg = (
            f"{what} must be {len(names)} numbers ({', '.join(names)}), "
            f"got {len(items)}: {show(values)}"
        )
        raise InvalidPoseError(msg)
    return [finite_float(name, item) for name, item in zip(names, items, strict=True)]


def rigid_matrix(value: object) -> Matrix:
    """Return ``value`` as a float64 4x4 rigid transform, validated.

    Accepts a numpy array or a nested sequence of 4 rows of 4 numbers. The
    rotation block must be orthonormal within `UNIT_TOLERANCE` with
    determinant +1, and the last row exactly ``[0, 0, 0, 1]``.

    Raises:
        InvalidPoseError: Naming the value and what is wrong with it.
    """
    problem = _matrix_shape_problem(value)
    matrix = np.asarray(value, dtype=np.float64) if problem is None else None
    if matrix is not None:
        problem = _rigidity_problem(matrix)
    if problem is None and matrix is not None:
        return matrix
    msg = f"expected a 4x4 rigid transform, got {show(value)}: {problem}"
    raise InvalidPoseError(msg)


def _matrix_shape_problem(value: object) -> str | None:
    if isinstance(value, np.ndarray):
        if value.shape != (4, 4):
            return f"its shape is {value.shape}, not (4, 4)"
        if value.dtype.kind not in "iuf":
            return f"its dtype is {value.dtype}; expected real numbers"
        return None
    if isinstance(value, str | bytes) or not isinstance(value, Sequence) or len(value) != 4:
        return "expected 4 rows of 4 numbers"
    for row in value:
        if isinstance(row, np.ndarray):
            row = row.tolist()  # noqa: PLW2901  # rows may be 1-D arrays
        if isinstance(row, str | bytes) or not isinstance(row, Sequence) or len(row) != 4:
            return f"row {show(row)} is not 4 numbers"
        if not all(is_number(item) for item in row):
            return f"row {show(row)} holds something that is not a real number"
    return None


def _rigidity_problem(matrix: Matrix) -> str | None:
    if not np.isfinite(matrix).all():
        return "it holds non-finite entries"
    if tuple(matrix[3].tolist()) != _LAST_ROW:
        return f"its last row is {matrix[3].tolist()}, expected [0.0, 0.0, 0.0, 1.0]"
    rotation = matrix[:3, :3]
    error = float(np.abs(rotation @ rotation.T - np.eye(3)).max())
    if error > UNIT_TOLERANCE:
        return (
            f"its rotation block is not orthonormal "
            f"(max |R R^T - I| = {error:.3g} > {UNIT_TOLERANCE})"
        )
    if np.linalg.det(rotation) < 0:
        return "its rotation block is a reflection (determinant -1), not a rotation"
    return None


def invert_rigid(matrix: Matrix) -> Matrix:
    """Return the inverse of a rigid transform (transpose the rotation, not a general inverse)."""
    rotation_t = matrix[:3, :3].T
    inverse = np.eye(4)
    inverse[:3, :3] = rotation_t
    inverse[:3, 3] = -rotation_t @ matrix[:3, 3]
    return inverse


def normalize_angle(angle: float) -> float:
    """Return ``angle`` (radians) wrapped into (-π, π]; -π itself becomes π."""
    wrapped = math.remainder(finite_float("angle", angle), TAU)
    return math.pi if wrapped <= -math.pi else wrapped


def angular_distance(a1: float, a2: float) -> float:
    """Return the signed angle (radians) that turns ``a1`` into ``a2``, in (-π, π]."""
    return normalize_angle(finite_float("a2", a2) - finite_float("a1", a1))


def quaternion_from_euler(rx: float, ry: float, rz: float) -> tuple[float, float, float, float]:
    """Return the ``(qx, qy, qz, qw)`` quaternion of static-axes sxyz Euler angles."""
    angles = finite_floats(("rx", "ry", "rz"), (rx, ry, rz), "Euler angles")
    w, x, y, z = (float(c) for c in t3d_euler.euler2quat(*angles, axes="sxyz"))
    return (x, y, z, w)


def point_xy(point: object, what: str = "point") -> tuple[float, float]:
    """Read an ``(x, y)`` or ``(x, y, z)`` point (z ignored) as two floats."""
    items = point.tolist() if isinstance(point, np.ndarray) else point
    names = ("x", "y", "z") if isinstance(items, Sequence) and len(items) == 3 else ("x", "y")
    x, y, *_ = finite_floats(names, items, what)
    return (x, y)


def isin(point: tuple[float, float], polygon: Iterable[object]) -> bool:
    """Whether a 2-D point lies in a polygon (even-odd rule), edges and vertices included."""
    vertices = _polygon(polygon)
    px, py = point
    inside = False
    for (ax, ay), (bx, by) in zip(vertices, vertices[1:] + vertices[:1], strict=True):
        if _segment_distance((px, py), (ax, ay), (bx, by)) <= EDGE_TOLERANCE:
            return True
        if (ay > py) != (by > py) and px < ax + (py - ay) * (bx - ax) / (by - ay):
            inside = not inside
    return inside


def _polygon(polygon: Iterable[object]) -> list[tuple[float, float]]:
    items = polygon.tolist() if isinstance(polygon, np.ndarray) else polygon
    if isinstance(items, str | bytes) or not isinstance(items, Iterable):
        msg = f"a polygon must be a sequence of (x, y) vertices, got {show(polygon)}"
        raise InvalidPoseError(msg)
    vertices = [point_xy(vertex, "a polygon vertex") for vertex in items]
    if len(vertices) < 3:
        msg = f"a polygon needs at least 3 vertices, got {len(vertices)}: {show(polygon)}"
        raise InvalidPoseError(msg)
    return vertices


def _segment_distance(
    point: tuple[float, float], a: tuple[float, float], b: tuple[float, float]
) -> float:
    (px, py), (ax, ay), (bx, by) = point, a, b
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    return math.hypot(px - (ax + t * dx), py - (ay + t * dy))
