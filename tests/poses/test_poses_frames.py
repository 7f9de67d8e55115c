"""Frames: `FrameTree`, `FrameProvider`s and how a `PoseManager` combines them."""

from __future__ import annotations

import math
from collections.abc import Collection

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pyrobots_aio import InvalidPoseError, PoseError, UnknownFrameError
from pyrobots_aio.poses import FrameProvider, FrameTree, Pose, PoseManager

HALF = math.sqrt(0.5)
# A -> B -> A round trips through chains of a few 4x4 products: float64 error ~1e-13 at
# 100 m; 1e-9 catches any wrong inverse or order (those are off by metres).
TOL = 1e-9


class Odometry:
    """A provider like the simulator's: odom at the map origin (so base_link's pose in odom
    is also its transform to map), base_link moving."""

    def __init__(self) -> None:
        self.base = Pose(frame="odom")

    def get_transform(self, frame: str) -> np.ndarray:
        if frame == "odom":
            return np.eye(4)
        if frame == "base_link":
            return self.base.matrix()
        msg = f"unknown frame {frame!r}; known frames: ['base_link', 'odom']"
        raise UnknownFrameError(msg)

    def frames(self) -> Collection[str]:
        return ("odom", "base_link")


class Broken:
    """A provider that returns a 3x3 array."""

    def get_transform(self, frame: str) -> np.ndarray:
        return np.eye(3)

    def frames(self) -> Collection[str]:
        return ("broken",)


def chain() -> FrameTree:
    tree = FrameTree()
    tree.set_transform("map", "odom", (1.0, 0.0, 0.0))
    tree.set_transform("odom", "base_link", (0.0, 2.0, 0.0, 0.0, 0.0, math.pi / 2))
    return tree


def test_a_tree_composes_chains_up_to_map() -> None:
    tree = chain()
    expected = Pose(1.0, 2.0, 0.0, 0.0, 0.0, HALF, HALF)
    assert Pose.from_matrix(tree.get_transform("base_link")).isclose(expected, atol=1e-15)
    assert tree.get_transform("map").tolist() == np.eye(4).tolist()
    assert tree.frames() == {"map", "odom", "base_link"}
    assert tree.parent("base_link") == "odom"
    assert repr(tree) == "FrameTree(map->odom, odom->base_link)"
    assert isinstance(tree, FrameProvider)


def test_repeated_updates_are_seen_at_once() -> None:
    tree = chain()
    poses = PoseManager(tree)
    for step in range(5):
        yaw = 0.3 * step
        base = Pose.from_euler(0.1 * step, 0.0, 0.0, 0.0, 0.0, yaw, "odom")
        tree.set_transform("odom", "base_link", base.matrix())
        expected = Pose.from_euler(1.0 + 0.1 * step, 0.0, 0.0, 0.0, 0.0, yaw)
        assert poses.myself().isclose(expected, atol=1e-12)
        assert poses.inframe((1.0, 0.0, 0.0), "base_link").x == pytest.approx(
            -0.1 * step * math.cos(yaw), abs=1e-12
        )


def test_returned_transforms_are_not_the_trees_own_arrays() -> None:
    tree = chain()
    tree.get_transform("odom")[0, 3] = 99.0
    tree.get_transform("base_link")[0, 3] = 99.0
    assert tree.get_transform("odom")[0, 3] == 1.0
    matrix = np.eye(4)
    tree.set_transform("map", "dock", matrix)
    matrix[0, 3] = 5.0
    assert tree.get_transform("dock")[0, 3] == 0.0
    tree.set_transform("map", "dock", matrix)
    assert tree.get_transform("dock")[0, 3] == 5.0


def test_set_transform_accepts_poses_in_the_parent_and_raw_formats() -> None:
    tree = FrameTree()
    tree.set_transform("map", "a", Pose(1.0, frame="map"))
    tree.set_transform("a", "b", {"y": 1.0})
    tree.set_transform("b", "c", [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
    tree.set_transform("c", "d", (0, 0, 0, 0, 0, 1, 0, "c"))
    assert tree.get_transform("d")[:3, 3].tolist() == [1.0, 1.0, 1.0]
    with pytest.raises(InvalidPoseError) as info:
        tree.set_transform("a", "e", Pose(1.0))
    assert str(info.value) == (
        "the transform of 'a' -> 'e' must be a pose in 'a', got one in 'map': "
        "Pose(x=1.0, y=0.0, z=0.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='map')"
    )


def test_set_transform_rejects_bad_names_and_matrices() -> None:
    tree = FrameTree()
    with pytest.raises(InvalidPoseError, match=r"^parent must be a non-empty string, got ''$"):
        tree.set_transform("", "a", (0, 0, 0))
    with pytest.raises(InvalidPoseError, match=r"^child must be a non-empty string, got None$"):
        tree.set_transform("map", None, (0, 0, 0))  # type: ignore[arg-type]
    with pytest.raises(InvalidPoseError) as info:
        tree.set_transform("map", "a", np.diag([1.0, 1.0, 1.0, 0.0]))
    assert str(info.value) == (
        "expected a 4x4 rigid transform, got array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], "
        "[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0]]): "
        "its last row is [0.0, 0.0, 0.0, 0.0], expected [0.0, 0.0, 0.0, 1.0]"
    )
    assert tree.frames() == {"map"}


def test_a_frame_has_one_parent() -> None:
    tree = chain()
    with pytest.raises(PoseError) as info:
        tree.set_transform("map", "base_link", (0, 0, 0))
    assert str(info.value) == (
        "frame 'base_link' already has parent 'odom' and a frame has one parent; "
        "call remove_transform('base_link') first to move it under 'map'"
    )
    tree.remove_transform("base_link")
    tree.set_transform("map", "base_link", (3, 0, 0))
    assert tree.get_transform("base_link")[0, 3] == 3.0


def test_cycles_and_map_as_a_child_are_rejected() -> None:
    tree = FrameTree()
    tree.set_transform("a", "b", (0, 0, 0))
    tree.set_transform("b", "c", (0, 0, 0))
    with pytest.raises(PoseError) as info:
        tree.set_transform("c", "a", (0, 0, 0))
    assert (
        str(info.value)
        == "cannot make 'a' a child of 'c': the frames would form a cycle a->b->c->a"
    )
    with pytest.raises(PoseError) as info:
        tree.set_transform("d", "d", (0, 0, 0))
    assert str(info.value) == "cannot make 'd' a child of 'd': the frames would form a cycle d->d"
    with pytest.raises(PoseError) as info:
        tree.set_transform("c", "map", (0, 0, 0))
    assert str(info.value) == "'map' is the root of every frame tree; it cannot be a child of 'c'"
    assert repr(tree) == "FrameTree(a->b, b->c)"


def test_tree_lookup_errors() -> None:
    tree = chain()
    tree.set_transform("torso", "head", (0, 0, 1))
    with pytest.raises(UnknownFrameError) as info:
        tree.get_transform("elbow")
    assert str(info.value) == (
        "unknown frame 'elbow'; known frames: ['base_link', 'head', 'map', 'odom']"
    )
    with pytest.raises(UnknownFrameError) as info:
        tree.get_transform("head")
    assert str(info.value) == (
        "frame 'head' hangs from 'torso', which this FrameTree does not place in 'map'; "
        "add the tree to a PoseManager whose other providers know 'torso'"
    )
    assert tree.resolve("head")[0] == "torso"
    with pytest.raises(UnknownFrameError) as info:
        tree.remove_transform("torso")
    assert str(info.value) == (
        "frame 'torso' has no parent in this FrameTree; children: ['base_link', 'head', 'odom']"
    )
    with pytest.raises(UnknownFrameError, match=r"^frame 'map' has no parent in this"):
        tree.parent("map")


def test_a_tree_chain_is_completed_by_other_providers() -> None:
    odometry = Odometry()
    head = FrameTree()
    head.set_transform("base_link", "head", (0.0, 0.0, 1.0))
    poses = PoseManager(odometry, head)
    assert poses.frames() == {"map", "odom", "base_link", "head"}
    odometry.base = Pose(2.0, 0.0, 0.0, 0.0, 0.0, HALF, HALF, "odom")
    assert poses.inframe("head", "map").isclose(
        Pose(2.0, 0.0, 1.0, 0.0, 0.0, HALF, HALF), atol=1e-15
    )
    odometry.base = Pose(3.0, frame="odom")
    assert poses.inframe("head", "map").isclose(Pose(3.0, 0.0, 1.0), atol=1e-15)


def test_unknown_frames_list_what_every_provider_knows() -> None:
    arm = FrameTree()
    arm.set_transform("torso", "hand", (0.5, 0.0, 0.0))
    poses = PoseManager(Odometry(), arm)
    with pytest.raises(UnknownFrameError) as info:
        poses.get_transform("elbow")
    assert str(info.value) == (
        "unknown frame 'elbow'; known frames: ['base_link', 'hand', 'map', 'odom']"
    )
    with pytest.raises(UnknownFrameError) as info:
        poses.inframe("hand", "map")
    assert str(info.value) == (
        "unknown frame 'torso' (the parent of 'hand'); "
        "known frames: ['base_link', 'hand', 'map', 'odom']"
    )


def test_the_first_provider_that_knows_a_frame_wins() -> None:
    near, far = FrameTree(), FrameTree()
    near.set_transform("map", "dock", (1.0, 0.0, 0.0))
    far.set_transform("map", "dock", (9.0, 0.0, 0.0))
    far.set_transform("map", "door", (5.0, 0.0, 0.0))
    poses = PoseManager(near, far)
    assert poses.get_transform("dock")[0, 3] == 1.0
    assert poses.get_transform("door")[0, 3] == 5.0
    poses.remove_frame_provider(near)
    assert poses.providers == (far,)
    assert poses.get_transform("dock")[0, 3] == 9.0
    poses.add_frame_provider(near)
    assert poses.providers == (far, near)
    assert poses.get_transform("dock")[0, 3] == 9.0


def test_map_is_always_known() -> None:
    poses = PoseManager()
    assert poses.frames() == {"map"}
    assert poses.get_transform("map").tolist() == np.eye(4).tolist()
    with pytest.raises(UnknownFrameError) as info:
        poses.myself()
    assert str(info.value) == "unknown frame 'base_link'; known frames: ['map']"


def test_provider_registration_errors() -> None:
    tree = chain()
    poses = PoseManager(tree)
    with pytest.raises(PoseError) as info:
        poses.add_frame_provider(tree)
    assert str(info.value) == (
        "FrameTree(map->odom, odom->base_link) is already a frame provider of this PoseManager"
    )
    with pytest.raises(PoseError) as info:
        poses.add_frame_provider("tf")  # type: ignore[arg-type]
    assert str(info.value) == (
        "'tf' is not a FrameProvider: it needs get_transform(frame) and frames() methods"
    )
    with pytest.raises(PoseError) as info:
        poses.add_frame_provider(poses)
    assert str(info.value) == "a PoseManager cannot be its own frame provider"
    with pytest.raises(PoseError) as info:
        poses.remove_frame_provider(FrameTree())
    assert str(info.value) == "FrameTree() is not a frame provider of this PoseManager"
    assert poses.providers == (tree,)
    assert repr(poses) == "PoseManager(FrameTree(map->odom, odom->base_link))"


def test_a_provider_returning_a_non_4x4_array_is_named() -> None:
    poses = PoseManager()
    poses.add_frame_provider(Broken())
    with pytest.raises(PoseError) as info:
        poses.get_transform("broken")
    assert str(info.value).endswith(
        " returned array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) for 'broken'; "
        "expected a 4x4 transform"
    )
    assert str(info.value).startswith("frame provider <")


def test_a_cycle_across_providers_is_reported() -> None:
    first, second = FrameTree(), FrameTree()
    first.set_transform("b", "a", (0, 0, 0))
    second.set_transform("a", "b", (0, 0, 0))
    poses = PoseManager(first, second)
    with pytest.raises(PoseError) as info:
        poses.get_transform("a")
    assert str(info.value) == "frames form a cycle across providers: a <- b <- a"


def test_a_manager_is_itself_a_frame_provider() -> None:
    inner = PoseManager(chain())
    outer = PoseManager(inner)
    assert isinstance(inner, FrameProvider)
    assert outer.get_transform("odom")[0, 3] == 1.0
    assert outer.frames() == {"map", "odom", "base_link"}


def test_two_managers_share_nothing() -> None:
    one, two = PoseManager(), PoseManager()
    one.add_frame_provider(chain())
    assert two.providers == ()
    assert two.frames() == {"map"}


angles = st.floats(-math.pi, math.pi)
coords = st.floats(-100.0, 100.0)
poses_in_odom = st.builds(Pose.from_euler, coords, coords, coords, angles, angles, angles)


@given(poses_in_odom, poses_in_odom, poses_in_odom)
def test_frame_a_to_b_to_a_round_trip(odom: Pose, base: Pose, p: Pose) -> None:
    """A pose in base_link, expressed in map then odom then back, within TOL (1e-9)."""
    tree = FrameTree()
    tree.set_transform("map", "odom", odom)
    tree.set_transform("odom", "base_link", Pose(*base.position(), *base.quat_xyzw(), "odom"))
    poses = PoseManager(tree)
    start = Pose(*p.position(), *p.quat_xyzw(), "base_link")
    in_map = poses.inframe(start, "map")
    in_odom = poses.inframe(in_map, "odom")
    assert poses.inframe(in_odom, "base_link").isclose(start, atol=TOL)
    assert poses.distance(in_map, start) == pytest.approx(0.0, abs=TOL)


class Planar(Odometry):
    """The same frames, read in the floor plane too (as the simulator's `get_planar`)."""

    def __init__(self) -> None:
        super().__init__()
        self.planar_reads: list[str] = []

    def get_planar(self, frame: str) -> tuple[float, float, float]:
        self.planar_reads.append(frame)
        (r0, _, _, x), (r1, _, _, y) = self.get_transform(frame)[:2].tolist()
        return (x, y, math.atan2(r1, r0))


@pytest.mark.parametrize("provider", [Odometry, Planar])
def test_planar_gives_get_transform_s_floor_plane_numbers(provider: type[Odometry]) -> None:
    odometry, poses, tree = provider(), PoseManager(), FrameTree()
    odometry.base = Pose.from_euler(1.5, -2.0, 0.0, 0.0, 0.0, 2.5, "odom")
    tree.set_transform("base_link", "arm", (0.2, 0.1, 0.4, 0.0, 0.0, -1.0))
    poses.add_frame_provider(odometry)
    poses.add_frame_provider(tree)
    for frame in ("odom", "base_link", "arm", "map"):
        (r0, _, _, x), (r1, _, _, y) = poses.get_transform(frame)[:2].tolist()
        assert poses.planar(frame) == (x, y, math.atan2(r1, r0))  # exactly
    assert poses.planar("base_link") == pytest.approx((1.5, -2.0, 2.5))
    if isinstance(odometry, Planar):  # read directly where the provider knows the frame
        assert odometry.planar_reads[:2] == ["odom", "base_link"]
    with pytest.raises(UnknownFrameError, match="'gripper'"):
        poses.planar("gripper")


def test_planar_asks_the_providers_of_now() -> None:
    # The manager keeps its providers' planar readers: adding or removing one renews them.
    poses, odometry = PoseManager(), Planar()
    odometry.base = Pose.from_euler(1.5, -2.0, 0.0, 0.0, 0.0, 2.5, "odom")
    with pytest.raises(UnknownFrameError, match="'base_link'"):
        poses.planar("base_link")
    poses.add_frame_provider(odometry)
    assert poses.planar("base_link") == pytest.approx((1.5, -2.0, 2.5))
    assert odometry.planar_reads == ["base_link"]
    poses.remove_frame_provider(odometry)
    with pytest.raises(UnknownFrameError, match="'base_link'"):
        poses.planar("base_link")
    assert odometry.planar_reads == ["base_link"]
