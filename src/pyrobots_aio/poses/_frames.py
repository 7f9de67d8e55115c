"""Where frames come from: the `FrameProvider` protocol and the `FrameTree` provider."""

from __future__ import annotations

from collections.abc import Collection
from typing import Protocol, runtime_checkable

import numpy as np

from .._exceptions import InvalidPoseError, PoseError, UnknownFrameError
from ._math import Matrix, rigid_matrix
from ._parse import PoseLike, parse_pose
from ._pose import frame_name

MAP = "map"
"""The world frame every provider places its frames in; always known, the identity."""


@runtime_checkable
class FrameProvider(Protocol):
    """A source of frames, placed in ``map`` (TF's broadcasters, the simulator).

    Examples:
        >>> class Fixed:
        ...     def get_transform(self, frame: str) -> Matrix:
        ...         if frame != "charger":
        ...             raise UnknownFrameError(f"unknown frame {frame!r}")
        ...         m = np.eye(4)
        ...         m[:3, 3] = (2.0, 0.0, 0.0)
        ...         return m
        ...
        ...     def frames(self) -> Collection[str]:
        ...         return ("charger",)
        >>> isinstance(Fixed(), FrameProvider)
        True
    """

    def get_transform(self, frame: str) -> Matrix:
        """Return the 4x4 transform from ``frame`` to ``map``.

        It maps points expressed in ``frame`` to the same points expressed in
        ``map`` (its last column is the frame's origin in ``map``). Callers
        do not mutate it; return a fresh array or one the provider will not
        change afterwards.

        Raises:
            UnknownFrameError: The provider does not know ``frame`` (listing
                the frames it knows).
        """
        ...

    def frames(self) -> Collection[str]:
        """Return the names of the frames this provider can place, for error messages."""
        ...


class FrameTree:
    """A tree of static or updatable transforms between named frames, like TF.

    Each edge ``parent -> child`` holds the pose of ``child``'s origin in
    ``parent``. Chains are composed up to ``map`` at every lookup: nothing
    is cached, so an update is seen by the next lookup. Updating an existing
    edge copies the new matrix into the edge's own array (no growth, a few
    small temporaries for validation), so the simulator can update
    ``odom -> base_link`` every tick.

    A chain whose top frame is not ``map`` (``base_link -> head`` when the
    simulator owns ``base_link``) is completed by the other providers of the
    `PoseManager` it is added to; on its own, the tree raises
    `UnknownFrameError` for it.

    Examples:
        >>> tree = FrameTree()
        >>> tree.set_transform("map", "odom", (0.0, 0.0, 0.0))
        >>> tree.set_transform("odom", "base_link", (1.0, 2.0, 0.0))
        >>> tree.get_transform("base_link")[:3, 3].tolist()
        [1.0, 2.0, 0.0]
    """

    __slots__ = ("_edges", "_parents")

    def __init__(self) -> None:
        self._parents: dict[str, str] = {}
        self._edges: dict[str, Matrix] = {}

    def set_transform(self, parent: str, child: str, transform: PoseLike) -> None:
        """Add the edge ``parent -> child`` or update its transform.

        Args:
            parent: The parent frame.
            child: The child frame; a frame has at most one parent.
            transform: The pose of ``child``'s origin in ``parent``: a 4x4
                rigid matrix (numpy array: the fast path for updates), a
                `Pose` whose ``frame`` is ``parent``, or any format of
                `PoseManager.get`; formats without a frame are read in
                ``parent``.

        Raises:
            InvalidPoseError: A frame name is empty or not a string, or
                ``transform`` is not a pose (or a `Pose` in another frame).
            PoseError: ``child`` already has another parent, is ``map``, or
                the edge would close a cycle.
        """
        frame_name(parent, "parent")
        frame_name(child, "child")
        matrix = _edge_matrix(parent, child, transform)
        current = self._parents.get(child)
        if current == parent:
            np.copyto(self._edges[child], matrix)
            return
        self._check_new_edge(parent, child, current)
        self._parents[child] = parent
        self._edges[child] = np.array(matrix, dtype=np.float64)

    def remove_transform(self, child: str) -> None:
        """Remove the edge to ``child`` (its own children then hang from it).

        Raises:
            UnknownFrameError: ``child`` has no parent in this tree.
        """
        if child not in self._parents:
            msg = f"frame {child!r} has no parent in this FrameTree; children: {self._children()}"
            raise UnknownFrameError(msg)
        del self._parents[child], self._edges[child]

    def parent(self, child: str) -> str:
        """Return the parent of ``child``.

        Raises:
            UnknownFrameError: ``child`` has no parent in this tree.
        """
        try:
            return self._parents[child]
        except KeyError:
            msg = f"frame {child!r} has no parent in this FrameTree; children: {self._children()}"
            raise UnknownFrameError(msg) from None

    def resolve(self, frame: str) -> tuple[str, Matrix]:
        """Return the top ancestor of ``frame`` in this tree and the transform to it.

        The transform maps points in ``frame`` to points in that ancestor
        (``map`` when the chain is complete). Used by `PoseManager` to
        complete chains through other providers.

        Raises:
            UnknownFrameError: ``frame`` is neither ``map`` nor a child here.
        """
        if frame == MAP:
            return (MAP, np.eye(4))
        if frame not in self._parents:
            msg = f"unknown frame {frame!r}; known frames: {sorted(self.frames())}"
            raise UnknownFrameError(msg)
        matrix = self._edges[frame].copy()
        top = self._parents[frame]
        while top in self._parents:
            matrix = self._edges[top] @ matrix
            top = self._parents[top]
        return (top, matrix)

    def get_transform(self, frame: str) -> Matrix:
        """Return the transform from ``frame`` to ``map`` (see `FrameProvider`).

        Raises:
            UnknownFrameError: ``frame`` is not in this tree, or its chain
                stops at a frame other than ``map``.
        """
        top, matrix = self.resolve(frame)
        if top != MAP:
            msg = (
                f"frame {frame!r} hangs from {top!r}, which this FrameTree does not place "
                f"in 'map'; add the tree to a PoseManager whose other providers know {top!r}"
            )
            raise UnknownFrameError(msg)
        return matrix

    def has(self, frame: str) -> bool:
        """Whether ``frame`` is ``map`` or has a parent in this tree (`resolve` takes it).

        Examples:
            >>> tree = FrameTree()
            >>> tree.set_transform("base_link", "arm", (0.1, 0.0, 0.3))
            >>> tree.has("arm"), tree.has("map"), tree.has("gripper")
            (True, True, False)
        """
        return frame == MAP or frame in self._parents

    def frames(self) -> frozenset[str]:
        """Return ``map`` and every frame that has a parent in this tree."""
        return frozenset((MAP, *self._parents))

    def __repr__(self) -> str:
        edges = ", ".join(f"{parent}->{child}" for child, parent in self._parents.items())
        return f"FrameTree({edges})"

    def _children(self) -> list[str]:
        return sorted(self._parents)

    def _check_new_edge(self, parent: str, child: str, current: str | None) -> None:
        if current is not None:
            msg = (
                f"frame {child!r} already has parent {current!r} and a frame has one parent; "
                f"call remove_transform({child!r}) first to move it under {parent!r}"
            )
            raise PoseError(msg)
        if child == MAP:
            msg = f"'map' is the root of every frame tree; it cannot be a child of {parent!r}"
            raise PoseError(msg)
        chain = [child, parent]
        while chain[-1] != child and chain[-1] in self._parents:
            chain.append(self._parents[chain[-1]])
        if chain[-1] == child:
            msg = (
                f"cannot make {child!r} a child of {parent!r}: "
                f"the frames would form a cycle {'->'.join(reversed(chain))}"
            )
            raise PoseError(msg)


def _edge_matrix(parent: str, child: str, transform: object) -> Matrix:
    if isinstance(transform, np.ndarray) and transform.ndim == 2:
        return rigid_matrix(transform)
    pose = parse_pose(transform, default_frame=parent)
    if pose.frame != parent:
        msg = (
            f"the transform of {parent!r} -> {child!r} must be a pose in {parent!r}, "
            f"got one in {pose.frame!r}: {pose!r}"
        )
        raise InvalidPoseError(msg)
    return pose.matrix()
