"""Geometry on a `PoseManager`: inframe, distance, myself, pantilt, angles, polygons."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pyrobots_aio import InvalidPoseError, UnknownFrameError
from pyrobots_aio.poses import FrameTree, Pose, PoseManager

HALF = math.sqrt(0.5)
PI = math.pi


def robot_at(x: float, y: float, yaw: float, head_height: float = 1.0) -> PoseManager:
    """map -> odom (identity) -> base_link (x, y, yaw) -> head (head_height up)."""
    tree = FrameTree()
    tree.set_transform("map", "odom", (0.0, 0.0, 0.0))
    tree.set_transform("odom", "base_link", (x, y, 0.0, 0.0, 0.0, yaw))
    tree.set_transform("base_link", "head", (0.0, 0.0, head_height))
    return PoseManager(tree)


def test_inframe_moves_position_and_orientation() -> None:
    poses = robot_at(1.0, 0.0, PI / 2)
    # One metre along map +y from the robot is straight ahead of it.
    ahead = poses.inframe((1.0, 1.0, 0.0), "base_link")
    assert ahead.isclose(Pose(1.0, 0.0, 0.0, 0.0, 0.0, -HALF, HALF, "base_link"), atol=1e-15)
    back = poses.inframe(ahead, "map")
    assert back.isclose(Pose(1.0, 1.0, 0.0), atol=1e-15)
    assert poses.inframe("head", "map").isclose(
        Pose(1.0, 0.0, 1.0, 0.0, 0.0, HALF, HALF), atol=1e-15
    )


def test_inframe_to_the_same_frame_is_the_same_pose() -> None:
    poses = robot_at(1.0, 0.0, 0.3)
    p = Pose(1.0, 2.0, 3.0, frame="base_link")
    assert poses.inframe(p, "base_link") is p


def test_inframe_checks_the_target_frame() -> None:
    poses = robot_at(0.0, 0.0, 0.0)
    with pytest.raises(UnknownFrameError) as info:
        poses.inframe((1, 2, 3), "hed")
    assert str(info.value) == (
        "unknown frame 'hed'; known frames: ['base_link', 'head', 'map', 'odom']"
    )
    with pytest.raises(InvalidPoseError, match=r"^frame must be a non-empty string, got ''$"):
        poses.inframe((1, 2, 3), "")


def test_myself_is_base_link_in_map() -> None:
    poses = robot_at(2.0, -1.0, PI / 2)
    assert poses.myself().isclose(Pose(2.0, -1.0, 0.0, 0.0, 0.0, HALF, HALF), atol=1e-15)


def test_distance_is_between_positions_in_one_frame() -> None:
    poses = robot_at(1.0, 1.0, 0.7)
    assert poses.distance((4.0, 5.0, 0.0)) == pytest.approx(5.0, abs=1e-12)
    assert poses.distance((4.0, 5.0, 0.0), "map") == pytest.approx(math.hypot(4.0, 5.0))
    assert poses.distance("head", "base_link") == pytest.approx(1.0, abs=1e-15)
    assert poses.distance((0, 0, 0, "head"), (1.0, 1.0, 1.0, PI, 0.0, 0.0)) == pytest.approx(
        0.0, abs=1e-15
    )


def test_euler_of_a_raw_pose() -> None:
    poses = robot_at(0.0, 0.0, 0.0)
    assert poses.euler((0, 0, 0, 0.1, -0.2, 0.3, "odom")) == pytest.approx(
        (0.1, -0.2, 0.3), abs=1e-15
    )
    assert poses.euler("base_link") == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("target", "ref", "expected"),
    [
        # The pyRobots paper's look-at: a point one metre to the robot's left.
        ((0, 1, 0, "base_link"), "base_link", (PI / 2, 0.0)),
        # Seen from a head 1 m up, the same point is 45 degrees down: tilt +π/4.
        ((0, 1, 0, "base_link"), "head", (PI / 2, PI / 4)),
        ((1, 0, 0, "base_link"), "head", (0.0, PI / 4)),
        ((0, -1, 0, "base_link"), "base_link", (-PI / 2, 0.0)),
        ((-1, 0, 0, "base_link"), "base_link", (PI, 0.0)),
        ((1, 1, 0, "base_link"), "base_link", (PI / 4, 0.0)),
        # Above: negative tilt (looking up); straight above: pan 0, tilt -π/2.
        ((1, 0, 1, "base_link"), "base_link", (0.0, -PI / 4)),
        ((0, 0, 2, "base_link"), "base_link", (0.0, -PI / 2)),
        ((0, 0, 0, "base_link"), "base_link", (0.0, 0.0)),
        # Targets in map, robot at (1, 0) facing +y: (1, 1) is ahead, (0, 0) to its left.
        ((1, 1, 0), "base_link", (0.0, 0.0)),
        ((1, 0, -1), "head", (0.0, PI / 2)),
        ((0, 0, 0), "base_link", (PI / 2, 0.0)),
    ],
)
def test_pantilt_hand_computed(
    target: tuple[float | str, ...], ref: str, expected: tuple[float, float]
) -> None:
    poses = robot_at(1.0, 0.0, PI / 2)
    assert poses.pantilt(target, ref) == pytest.approx(expected, abs=1e-12)


def test_pantilt_defaults_to_base_link() -> None:
    poses = robot_at(0.0, 0.0, 0.0)
    assert poses.pantilt((0, 1, 0)) == pytest.approx((PI / 2, 0.0), abs=1e-15)


coords = st.floats(-10.0, 10.0)


@given(st.tuples(coords, coords, coords).filter(lambda p: math.hypot(*p) > 1e-3))
def test_pantilt_points_the_x_axis_at_the_target(target: tuple[float, float, float]) -> None:
    """Yaw by pan then pitch by tilt (sxyz (0, tilt, pan)) turns +x towards the target."""
    poses = robot_at(0.0, 0.0, 0.0)
    pan, tilt = poses.pantilt((*target, "base_link"))
    rotation = Pose.from_euler(0.0, 0.0, 0.0, 0.0, tilt, pan).matrix()[:3, :3]
    direction = np.array(target) / math.hypot(*target)
    np.testing.assert_allclose(rotation @ [1.0, 0.0, 0.0], direction, atol=1e-9)
    assert -PI <= pan <= PI
    assert -PI / 2 <= tilt <= PI / 2


def test_normalize_angle() -> None:
    assert PoseManager.normalize_angle(-PI) == PI
    assert PoseManager.normalize_angle(PI) == PI
    assert PoseManager.normalize_angle(0.0) == 0.0
    assert PoseManager.normalize_angle(2 * PI) == 0.0
    assert PoseManager.normalize_angle(-3 * PI / 2) == pytest.approx(PI / 2, abs=1e-15)
    assert PoseManager.normalize_angle(7.0) == pytest.approx(7.0 - 2 * PI, abs=1e-15)
    assert PoseManager.normalize_angle(-7.0) == pytest.approx(2 * PI - 7.0, abs=1e-15)
    with pytest.raises(InvalidPoseError, match=r"^angle must be a finite real number, got nan$"):
        PoseManager.normalize_angle(math.nan)


@given(st.floats(-1e6, 1e6))
def test_normalize_angle_lands_in_half_open_range(angle: float) -> None:
    wrapped = PoseManager.normalize_angle(angle)
    assert -PI < wrapped <= PI
    turns = (angle - wrapped) / (2 * PI)
    assert turns == pytest.approx(round(turns), abs=1e-9)


def test_angular_distance_is_oriented_and_wraps() -> None:
    assert PoseManager.angular_distance(3.0, -3.0) == pytest.approx(2 * PI - 6.0, abs=1e-15)
    assert PoseManager.angular_distance(-3.0, 3.0) == pytest.approx(6.0 - 2 * PI, abs=1e-15)
    assert PoseManager.angular_distance(0.1, 0.3) == pytest.approx(0.2, abs=1e-15)
    assert PoseManager.angular_distance(0.0, -PI / 2) == -PI / 2
    assert PoseManager.angular_distance(0.0, PI) == PI
    assert PoseManager.angular_distance(PI, 0.0) == PI
    assert PoseManager.angular_distance(1.0, 1.0 + 4 * PI) == pytest.approx(0.0, abs=1e-15)
    with pytest.raises(InvalidPoseError, match=r"^a1 must be a finite real number, got inf$"):
        PoseManager.angular_distance(math.inf, 0.0)


def test_quaternion_from_euler_is_x_first() -> None:
    assert PoseManager.quaternion_from_euler(0.0, 0.0, PI / 2) == pytest.approx(
        (0.0, 0.0, HALF, HALF), abs=1e-15
    )
    assert PoseManager.quaternion_from_euler(PI, 0.0, 0.0) == pytest.approx(
        (1.0, 0.0, 0.0, 0.0), abs=1e-15
    )
    with pytest.raises(InvalidPoseError, match=r"^ry must be a finite real number, got 'up'$"):
        PoseManager.quaternion_from_euler(0.0, "up", 0.0)  # type: ignore[arg-type]


# A U: two arms (x in [0, 1] and [2, 3]) joined by a base (y in [0, 1]); the notch
# x in (1, 2), y in (1, 3] is outside. Edges and vertices count as inside.
U_SHAPE = [(0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3)]


@pytest.mark.parametrize(
    ("point", "inside"),
    [
        ((0.5, 2.0), True),  # left arm
        ((2.5, 2.0), True),  # right arm
        ((1.5, 0.5), True),  # base
        ((1.5, 2.0), False),  # in the notch
        ((1.5, 1.0 + 1e-6), False),  # just inside the notch
        ((1.5, 3.0), False),  # the notch's open top
        ((1.5, 1.0), True),  # on the notch's floor (an edge)
        ((1.0, 2.0), True),  # on the notch's left wall
        ((3.0, 1.5), True),  # on the outer right edge
        ((0.5, 3.0), True),  # on the top of the left arm
        ((1.5, 1.0 - 1e-12), True),  # within EDGE_TOLERANCE of the floor
        ((0.0, 0.0), True),  # convex vertex
        ((2.0, 1.0), True),  # reflex vertex
        ((1.0, 3.0), True),  # vertex at the notch's opening
        ((0.5, 1.0), True),  # a ray through the reflex vertices' height
        ((2.5, 1.0), True),
        ((-1.0, 1.0), False),
        ((4.0, 3.0), False),  # a ray through the top vertices' height
        ((-1e-6, 1.5), False),
        ((1.5, -0.1), False),
    ],
)
def test_isin_concave_polygon(point: tuple[float, float], inside: bool) -> None:
    assert PoseManager.isin(point, U_SHAPE) is inside


def test_isin_accepts_poses_3d_points_and_arrays() -> None:
    polygon = np.array(U_SHAPE, dtype=float)
    assert PoseManager.isin(Pose(0.5, 2.0, 9.0), polygon)
    assert not PoseManager.isin(Pose(1.5, 2.0), polygon)
    assert PoseManager.isin((2.5, 2.0, -4.0), [(x, y, 0.0) for x, y in U_SHAPE])
    assert PoseManager.isin(np.array([0.5, 0.5]), U_SHAPE)


def test_isin_rejects_malformed_input() -> None:
    with pytest.raises(InvalidPoseError) as info:
        PoseManager.isin((0, 0), [(0, 0), (1, 1)])
    assert str(info.value) == "a polygon needs at least 3 vertices, got 2: [(0, 0), (1, 1)]"
    with pytest.raises(InvalidPoseError) as info:
        PoseManager.isin((0, 0), [(0, 0), (1, 1), (1,)])
    assert str(info.value) == "a polygon vertex must be 2 numbers (x, y), got 1: (1,)"
    with pytest.raises(InvalidPoseError) as info:
        PoseManager.isin((0, math.nan), U_SHAPE)
    assert str(info.value) == "y must be a finite real number, got nan"
    with pytest.raises(InvalidPoseError) as info:
        PoseManager.isin("here", U_SHAPE)  # type: ignore[arg-type]
    assert str(info.value) == "point must be a sequence of 2 numbers, got 'here'"
    with pytest.raises(InvalidPoseError) as info:
        PoseManager.isin((0, 0), 3)  # type: ignore[arg-type]
    assert str(info.value) == "a polygon must be a sequence of (x, y) vertices, got 3"
