"""`Pose`: construction, validation, accessors, named constructors, round trips."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pyrobots_aio import InvalidPoseError, PoseError
from pyrobots_aio.poses import Pose, PoseManager
from pyrobots_aio.poses._math import UNIT_TOLERANCE

HALF = math.sqrt(0.5)
# Round-trip tolerance: float64 rotations composed a few times stay within ~1e-13;
# 1e-9 leaves room without hiding a wrong convention (errors of those are O(0.1)).
TOL = 1e-9

angles = st.floats(-math.pi, math.pi)
# Away from gimbal lock (|ry| = π/2), where sxyz angles are not unique.
pitches = st.floats(-math.pi / 2 + 0.01, math.pi / 2 - 0.01)
coords = st.floats(-100.0, 100.0)
positions = st.tuples(coords, coords, coords)
eulers = st.tuples(angles, pitches, angles)


@st.composite
def unit_quaternions(draw: st.DrawFn) -> tuple[float, float, float, float]:
    q = np.array(draw(st.tuples(*[st.floats(-1.0, 1.0)] * 4)))
    norm = float(np.linalg.norm(q))
    if norm < 0.1:
        return (0.0, 0.0, 0.0, 1.0)
    x, y, z, w = (float(c) for c in q / norm)
    return (x, y, z, w)


def same_angle(a: float, b: float) -> bool:
    return abs(PoseManager.angular_distance(a, b)) <= TOL


def test_defaults_are_the_origin_of_map() -> None:
    assert Pose() == Pose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, "map")
    assert repr(Pose(1, 2, 3, frame="odom")) == (
        "Pose(x=1.0, y=2.0, z=3.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='odom')"
    )


def test_numbers_are_stored_as_plain_floats() -> None:
    p = Pose(1, np.float32(2.5), np.int64(3), frame="odom")
    assert (p.x, p.y, p.z) == (1.0, 2.5, 3.0)
    assert [type(v) for v in (p.x, p.y, p.z, p.qw)] == [float] * 4


def test_pose_is_frozen_hashable_and_slotted() -> None:
    p = Pose(1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.x = 2.0  # type: ignore[misc]
    assert not hasattr(p, "__dict__")
    assert len({Pose(1.0), Pose(1), Pose(2.0)}) == 2


def test_near_unit_quaternion_is_normalised() -> None:
    p = Pose(qz=0.7071, qw=0.7071)
    assert p.qz == p.qw == pytest.approx(HALF, abs=1e-15)
    assert math.hypot(p.qz, p.qw) == pytest.approx(1.0, abs=1e-15)
    # Just inside the tolerance: normalised; exact unit: untouched.
    assert Pose(qw=1.0 + 0.9 * UNIT_TOLERANCE).qw == 1.0
    assert Pose(qx=0.6, qw=0.8).quat_xyzw().tolist() == [0.6, 0.0, 0.0, 0.8]


def test_non_unit_and_zero_quaternions_are_rejected() -> None:
    with pytest.raises(InvalidPoseError) as info:
        Pose(qw=1.0 + 1.1 * UNIT_TOLERANCE)
    assert str(info.value) == (
        "quaternion (qx, qy, qz, qw) = (0.0, 0.0, 0.0, 1.0011) has norm 1.0011; "
        "expected a unit quaternion (norm within 0.001 of 1)"
    )
    with pytest.raises(InvalidPoseError) as info:
        Pose(qw=0)
    assert str(info.value) == (
        "quaternion (qx, qy, qz, qw) = (0.0, 0.0, 0.0, 0.0) is zero; "
        "expected a unit quaternion, e.g. the identity (0, 0, 0, 1)"
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"x": math.nan}, "x must be a finite real number, got nan"),
        ({"y": -math.inf}, "y must be a finite real number, got -inf"),
        ({"z": True}, "z must be a finite real number, got True (a bool is not a number)"),
        (
            {"qx": np.bool_(False)},
            "qx must be a finite real number, got np.False_ (a bool is not a number)",
        ),
        ({"qw": "1"}, "qw must be a finite real number, got '1'"),
        ({"qz": None}, "qz must be a finite real number, got None"),
        ({"x": 1j}, "x must be a finite real number, got 1j"),
        ({"frame": ""}, "frame must be a non-empty string, got ''"),
        ({"frame": 3}, "frame must be a non-empty string, got 3"),
    ],
)
def test_bad_fields_are_named(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(InvalidPoseError) as info:
        Pose(**kwargs)  # type: ignore[arg-type]
    assert str(info.value) == message
    assert isinstance(info.value, PoseError)
    assert isinstance(info.value, ValueError)


def test_a_frame_in_a_quaternion_slot_is_named() -> None:
    with pytest.raises(InvalidPoseError, match=r"^qx must be a finite real number, got 'odom'$"):
        Pose(1.0, 2.0, 3.0, "odom")  # type: ignore[arg-type]


def test_accessors_name_their_quaternion_order() -> None:
    p = Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF, "odom")
    assert p.position().tolist() == [1.0, 2.0, 3.0]
    assert p.position().dtype == np.float64
    assert p.quat_xyzw().tolist() == [0.0, 0.0, HALF, HALF]
    assert p.quat_wxyz().tolist() == [HALF, 0.0, 0.0, HALF]
    expected = np.array(
        [[0.0, -1.0, 0.0, 1.0], [1.0, 0.0, 0.0, 2.0], [0.0, 0.0, 1.0, 3.0], [0.0, 0.0, 0.0, 1.0]]
    )
    np.testing.assert_allclose(p.matrix(), expected, atol=1e-15)
    assert p.euler() == pytest.approx((0.0, 0.0, math.pi / 2), abs=1e-15)


def test_from_euler_is_static_xyz() -> None:
    # sxyz: roll about fixed x first, then yaw about fixed z: the body's y axis ends along -x.
    p = Pose.from_euler(0.0, 0.0, 0.0, math.pi / 2, 0.0, math.pi / 2, "odom")
    np.testing.assert_allclose(p.matrix()[:3, :3] @ [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], atol=1e-15)
    np.testing.assert_allclose(p.matrix()[:3, :3] @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    assert p.frame == "odom"
    with pytest.raises(InvalidPoseError, match=r"^ry must be a finite real number, got nan$"):
        Pose.from_euler(0.0, 0.0, 0.0, 0.0, math.nan, 0.0)


def test_from_wxyz_reads_w_first() -> None:
    p = Pose.from_wxyz(np.array([1.0, 2.0, 3.0]), [HALF, 0.0, 0.0, HALF], frame="dock")
    assert p == Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF, "dock")
    with pytest.raises(InvalidPoseError) as info:
        Pose.from_wxyz([1.0, 2.0], [1.0, 0.0, 0.0, 0.0])
    assert str(info.value) == "position must be 3 numbers (x, y, z), got 2: [1.0, 2.0]"
    with pytest.raises(InvalidPoseError) as info:
        Pose.from_wxyz([1.0, 2.0, 3.0], "wxyz")  # type: ignore[arg-type]
    assert str(info.value) == "quat_wxyz must be a sequence of 4 numbers, got 'wxyz'"


def test_from_matrix_reads_position_and_rotation() -> None:
    m = np.array([[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]])
    p = Pose.from_matrix(m, "odom")
    assert p.isclose(Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF, "odom"), atol=1e-15)
    assert Pose.from_matrix(m.tolist()).frame == "map"


def test_from_matrix_accepts_a_slightly_sloppy_rotation() -> None:
    typed = [[0.7071, -0.7071, 0, 0], [0.7071, 0.7071, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    assert Pose.from_matrix(typed).euler() == pytest.approx((0.0, 0.0, math.pi / 4), abs=1e-12)


@pytest.mark.parametrize(
    ("matrix", "problem"),
    [
        (np.eye(3), "its shape is (3, 3), not (4, 4)"),
        (np.eye(4, dtype=bool), "its dtype is bool; expected real numbers"),
        ("eye", "expected 4 rows of 4 numbers"),
        ([[1, 0, 0, 0]] * 3, "expected 4 rows of 4 numbers"),
        ([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], 7], "row 7 is not 4 numbers"),
        (
            [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, None, 1]],
            "row [0, 0, None, 1] holds something that is not a real number",
        ),
        (np.diag([1.0, 1.0, np.nan, 1.0]), "it holds non-finite entries"),
        (
            np.diag([1.0, 1.0, 1.0, 2.0]),
            "its last row is [0.0, 0.0, 0.0, 2.0], expected [0.0, 0.0, 0.0, 1.0]",
        ),
        (
            np.diag([2.0, 1.0, 1.0, 1.0]),
            "its rotation block is not orthonormal (max |R R^T - I| = 3 > 0.001)",
        ),
        (
            np.diag([1.0, 1.0, -1.0, 1.0]),
            "its rotation block is a reflection (determinant -1), not a rotation",
        ),
    ],
)
def test_from_matrix_rejects_non_rigid_matrices(matrix: object, problem: str) -> None:
    with pytest.raises(InvalidPoseError) as info:
        Pose.from_matrix(matrix)  # type: ignore[arg-type]
    shown = f"array({matrix.tolist()!r})" if isinstance(matrix, np.ndarray) else repr(matrix)
    assert str(info.value) == f"expected a 4x4 rigid transform, got {shown}: {problem}"


def test_isclose_treats_q_and_minus_q_as_one_rotation() -> None:
    p = Pose(1.0, 0.0, 0.0, 0.0, 0.0, HALF, HALF, "odom")
    assert p.isclose(Pose(1.0, 0.0, 0.0, 0.0, 0.0, -HALF, -HALF, "odom"))
    assert not p.isclose(Pose(1.0, 0.0, 0.0, 0.0, 0.0, HALF, -HALF, "odom"))
    assert not p.isclose(Pose(1.0, 0.0, 0.0, 0.0, 0.0, HALF, HALF, "map"))
    assert not p.isclose(Pose(1.001, 0.0, 0.0, 0.0, 0.0, HALF, HALF, "odom"))
    assert p.isclose(Pose(1.001, 0.0, 0.0, 0.0, 0.0, HALF, HALF, "odom"), atol=0.01)


def test_long_values_are_shortened_in_messages() -> None:
    with pytest.raises(InvalidPoseError) as info:
        Pose.from_matrix(list(range(100)))  # type: ignore[arg-type]
    message = str(info.value)
    assert re.fullmatch(
        r"expected a 4x4 rigid transform, got \[0, 1, 2, .{150,}\.\.\.: "
        r"expected 4 rows of 4 numbers",
        message,
    )


@given(positions, eulers)
def test_euler_matrix_quaternion_round_trip(
    position: tuple[float, float, float], euler: tuple[float, float, float]
) -> None:
    """Euler -> quaternion -> matrix -> quaternion -> Euler, within TOL (1e-9)."""
    rx, ry, rz = euler
    p = Pose.from_euler(*position, rx, ry, rz, "odom")
    back = Pose.from_matrix(p.matrix(), "odom")
    assert back.isclose(p, atol=TOL)
    brx, bry, brz = back.euler()
    assert same_angle(brx, rx)
    assert abs(bry - ry) <= TOL
    assert same_angle(brz, rz)
    assert PoseManager.quaternion_from_euler(rx, ry, rz) == pytest.approx(
        tuple(p.quat_xyzw().tolist()), abs=TOL
    )


@given(positions, unit_quaternions())
def test_quaternion_matrix_euler_round_trip(
    position: tuple[float, float, float], q: tuple[float, float, float, float]
) -> None:
    """Quaternion -> matrix -> quaternion and -> Euler -> quaternion, up to sign, within 1e-9."""
    p = Pose(*position, *q, frame="odom")
    assert Pose.from_matrix(p.matrix(), "odom").isclose(p, atol=TOL)
    assert Pose.from_euler(*position, *p.euler(), frame="odom").isclose(p, atol=TOL)
    assert Pose.from_wxyz(p.position(), p.quat_wxyz(), "odom") == p
