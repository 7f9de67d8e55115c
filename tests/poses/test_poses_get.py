"""`PoseManager.get`: every raw format of DESIGN.md §6, and every way to get one wrong."""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np
import pytest

from pyrobots_aio import InvalidPoseError, UnknownFrameError
from pyrobots_aio.poses import FrameTree, Pose, PoseManager

HALF = math.sqrt(0.5)
FORMATS = (
    "a frame name, (x, y, z[, frame]), (x, y, z, rx, ry, rz[, frame]) with sxyz Euler angles, "
    "(x, y, z, qx, qy, qz, qw[, frame]), a dict with keys among x y z qx qy qz qw frame, "
    "a Pose, or a 4x4 rigid matrix (with frame=...)"
)


def manager() -> PoseManager:
    tree = FrameTree()
    tree.set_transform("map", "odom", (1.0, 0.0, 0.0))
    tree.set_transform("odom", "base_link", (0.0, 1.0, 0.0))
    return PoseManager(tree)


POSES = manager()


def test_a_frame_name_is_the_origin_of_that_frame() -> None:
    assert POSES.get("base_link") == Pose(frame="base_link")
    assert POSES.get("map") == Pose()
    assert PoseManager().get("map") == Pose()


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        ((1, 2, 3), Pose(1.0, 2.0, 3.0)),
        ([1, 2, 3], Pose(1.0, 2.0, 3.0)),
        (np.array([1.0, 2.0, 3.0]), Pose(1.0, 2.0, 3.0)),
        ((1, 2, 3, "odom"), Pose(1.0, 2.0, 3.0, frame="odom")),
        ((1, 2, 3, 0, 0, math.pi / 2), Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF)),
        (
            (1, 2, 3, math.pi, 0, 0, "base_link"),
            Pose(1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0, "base_link"),
        ),
        ((1, 2, 3, 0, 0, 1, 0), Pose(1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 0.0)),
        (np.array([1, 2, 3, 0, 0, 1, 0]), Pose(1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 0.0)),
        ((1, 2, 3, 0, 0, 1, 0, "odom"), Pose(1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 0.0, "odom")),
        ((1, 2, 3, 0, 0, HALF, HALF, "odom"), Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF, "odom")),
    ],
)
def test_tuple_formats(raw: object, expected: Pose) -> None:
    assert POSES.get(raw).isclose(expected, atol=1e-15)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        ({}, Pose()),
        ({"x": 1}, Pose(1.0)),
        ({"y": 2.0, "frame": "odom"}, Pose(0.0, 2.0, frame="odom")),
        # Some quaternion keys given: the missing components are 0, not the identity's.
        ({"qz": 1.0}, Pose(qz=1.0, qw=0.0)),
        ({"qw": 1.0}, Pose()),
        ({"qz": HALF, "qw": HALF, "frame": "base_link"}, Pose(qz=HALF, qw=HALF, frame="base_link")),
        (
            {"x": 1, "y": 2, "z": 3, "qx": 0, "qy": 1, "qz": 0, "qw": 0, "frame": "odom"},
            Pose(1.0, 2.0, 3.0, 0.0, 1.0, 0.0, 0.0, "odom"),
        ),
        (OrderedDict(x=4.0), Pose(4.0)),
    ],
)
def test_dict_formats(raw: dict[str, float | str], expected: Pose) -> None:
    assert POSES.get(raw) == expected


def test_a_pose_is_returned_as_is() -> None:
    p = Pose(1.0, frame="odom")
    assert POSES.get(p) is p


def test_a_matrix_takes_its_frame_by_keyword() -> None:
    m = np.eye(4)
    m[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    m[:3, 3] = (1.0, 2.0, 3.0)
    expected = Pose(1.0, 2.0, 3.0, 0.0, 0.0, HALF, HALF, "base_link")
    assert POSES.get(m, frame="base_link").isclose(expected, atol=1e-15)
    assert POSES.get(m.tolist(), frame="base_link").isclose(expected, atol=1e-15)
    assert POSES.get([list(row) for row in m.astype(int)]).frame == "map"
    assert POSES.get(list(m)).frame == "map"  # a list of 1-D arrays


def test_unknown_frames_are_listed_for_every_format() -> None:
    message = "unknown frame 'odum'; known frames: ['base_link', 'map', 'odom']"
    m = np.eye(4)
    for raw in ("odum", (0, 0, 0, "odum"), {"frame": "odum"}, Pose(frame="odum")):
        with pytest.raises(UnknownFrameError) as info:
            POSES.get(raw)
        assert str(info.value) == message
    with pytest.raises(UnknownFrameError) as info:
        POSES.get(m, frame="odum")
    assert str(info.value) == message
    assert isinstance(info.value, KeyError)


@pytest.mark.parametrize(
    ("raw", "problem"),
    [
        ((1, 2), "a sequence of 2 items is not a pose"),
        ((1, 2, 3, 4), "a sequence of 4 items is not a pose"),
        ((1, 2, 3, 4, 5), "a sequence of 5 items is not a pose"),
        ((1, 2, 3, 4, 5, 6, 7, 8, 9), "a sequence of 9 items is not a pose"),
        ((), "a sequence of 0 items is not a pose"),
        (("odom",), "a sequence of 1 item is not a pose"),
        ({"x": 1, "w": 2, "rx": 1}, "unknown key(s) 'rx', 'w' in a pose dict"),
        ({1: 2}, "unknown key(s) 1 in a pose dict"),
        (3.5, "a float is not a pose"),
        (None, "a NoneType is not a pose"),
        (b"xyz", "a bytes is not a pose"),
        ({1.0, 2.0, 3.0}, "a set is not a pose"),
        # Not matrices: only 4 rows, or rows of 4, are read as a matrix.
        ((1, 2, 3, b"map"), "a sequence of 4 items is not a pose"),
        ([[1, 2, 3], "map"], "a sequence of 2 items is not a pose"),
        ([np.zeros(3), "map"], "a sequence of 2 items is not a pose"),
        (((1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0)), "a sequence of 2 items is not a pose"),
        ([[1, 2, 3], [0, 0, 0, 1], "odom"], "a sequence of 3 items is not a pose"),
        (
            np.array(["1", "2", "3"]),
            "a numpy array must be a 1-D numeric pose or a 4x4 matrix, got 1-D of dtype <U1",
        ),
        (
            np.array([True, False, True]),
            "a numpy array must be a 1-D numeric pose or a 4x4 matrix, got 1-D of dtype bool",
        ),
        (
            np.zeros((2, 2, 2)),
            "a numpy array must be a 1-D numeric pose or a 4x4 matrix, got 3-D of dtype float64",
        ),
    ],
)
def test_shapes_that_are_no_pose_list_the_formats(raw: object, problem: str) -> None:
    with pytest.raises(InvalidPoseError) as info:
        POSES.get(raw)  # type: ignore[arg-type]
    shown = f"array({raw.tolist()!r})" if isinstance(raw, np.ndarray) else repr(raw)
    assert str(info.value) == f"cannot read {shown} as a pose: {problem}; expected {FORMATS}"


@pytest.mark.parametrize(
    ("raw", "problem"),
    [
        ((1, 2, math.nan), "z must be a finite real number, got nan"),
        ((math.inf, 2, 3, "odom"), "x must be a finite real number, got inf"),
        ((1, True, 3), "y must be a finite real number, got True (a bool is not a number)"),
        ((1, 2, "3", "odom"), "z must be a finite real number, got '3'"),
        ((1, 2, 3, 0, math.nan, 0), "ry must be a finite real number, got nan"),
        (
            (1, 2, 3, 0, 0, 0, False),
            "qw must be a finite real number, got False (a bool is not a number)",
        ),
        (
            (1, 2, 3, 0, 0, 0, 0),
            "quaternion (qx, qy, qz, qw) = (0.0, 0.0, 0.0, 0.0) is zero; "
            "expected a unit quaternion, e.g. the identity (0, 0, 0, 1)",
        ),
        (
            (1, 2, 3, 0, 0, 0, 2, "odom"),
            "quaternion (qx, qy, qz, qw) = (0.0, 0.0, 0.0, 2.0) has norm 2; "
            "expected a unit quaternion (norm within 0.001 of 1)",
        ),
        (
            # Euler angles typed into quaternion slots.
            (1, 2, 3, 0.1, 0.2, 0.3, 0.4),
            "quaternion (qx, qy, qz, qw) = (0.1, 0.2, 0.3, 0.4) has norm 0.547723; "
            "expected a unit quaternion (norm within 0.001 of 1)",
        ),
        ((1, 2, 3, ""), "frame must be a non-empty string, got ''"),
        ("", "a frame name must be a non-empty string, got ''"),
        ({"x": "a"}, "x must be a finite real number, got 'a'"),
        ({"qz": None}, "qz must be a finite real number, got None"),
        ({"frame": 3}, "frame must be a non-empty string, got 3"),
        (
            {"qz": 1.0, "qw": 1.0},
            "quaternion (qx, qy, qz, qw) = (0.0, 0.0, 1.0, 1.0) has norm 1.41421; "
            "expected a unit quaternion (norm within 0.001 of 1)",
        ),
    ],
)
def test_bad_values_are_named(raw: object, problem: str) -> None:
    with pytest.raises(InvalidPoseError) as info:
        POSES.get(raw)  # type: ignore[arg-type]
    assert str(info.value) == f"cannot read {raw!r} as a pose: {problem}"


def test_frame_keyword_is_only_for_matrices() -> None:
    with pytest.raises(InvalidPoseError) as info:
        POSES.get((1, 2, 3), frame="odom")
    assert str(info.value) == (
        "cannot read (1, 2, 3) as a pose: frame='odom' is only for a 4x4 matrix; "
        f"put the frame inside the pose instead; expected {FORMATS}"
    )


@pytest.mark.parametrize(
    ("raw", "problem"),
    [
        (np.eye(3), "its shape is (3, 3), not (4, 4)"),
        ([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "expected 4 rows of 4 numbers"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 0]], "row [1, 0, 0] is not 4 numbers"),
        ([[1, 0, 0, 0], [0, 1, 0, 0]], "expected 4 rows of 4 numbers"),
        ([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], (0, 0, 1)], "row (0, 0, 1) is not 4 numbers"),
        (
            [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, True, 1]],
            "row [0, 0, True, 1] holds something that is not a real number",
        ),
        (np.full((4, 4), np.inf), "it holds non-finite entries"),
        (
            np.diag([1.0, 1.0, 1.0, 0.0]),
            "its last row is [0.0, 0.0, 0.0, 0.0], expected [0.0, 0.0, 0.0, 1.0]",
        ),
        (
            np.diag([1.0, 1.0, 0.5, 1.0]),
            "its rotation block is not orthonormal (max |R R^T - I| = 0.75 > 0.001)",
        ),
        (
            np.diag([-1.0, 1.0, 1.0, 1.0]),
            "its rotation block is a reflection (determinant -1), not a rotation",
        ),
    ],
)
def test_non_rigid_matrices_are_rejected(raw: object, problem: str) -> None:
    with pytest.raises(InvalidPoseError) as info:
        POSES.get(raw, frame="odom")  # type: ignore[arg-type]
    shown = f"array({raw.tolist()!r})" if isinstance(raw, np.ndarray) else repr(raw)
    assert str(info.value) == f"expected a 4x4 rigid transform, got {shown}: {problem}"
