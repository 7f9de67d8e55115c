"""`PoseManager` (``robot.poses``): reading poses and moving them between frames."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable

import numpy as np

from .._exceptions import PoseError, UnknownFrameError
from . import _math
from ._frames import MAP, FrameProvider, FrameTree
from ._math import Matrix, invert_rigid
from ._parse import PoseLike, parse_pose
from ._pose import Pose, Vector, frame_name

logger = logging.getLogger("pyrobots_aio.poses")


class PoseManager:
    """A robot's poses and frames (``robot.poses``).

    Frames come from `FrameProvider`s, asked in the order they were added:
    the first that knows a frame places it (``map`` is always known: the
    identity). A `FrameTree` whose chain stops at a frame it does not place
    (``base_link -> head``) is completed by the other providers.

    Every method taking a pose accepts any format of `get`.

    Args:
        *providers: Frame providers to add, in order.

    Examples:
        >>> tree = FrameTree()
        >>> tree.set_transform("map", "base_link", (1.0, 0.0, 0.0))
        >>> poses = PoseManager(tree)
        >>> poses.inframe((2.0, 0.0, 0.0), "base_link")
        Pose(x=1.0, y=0.0, z=0.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='base_link')
        >>> poses.distance((1.0, 3.0, 0.0))
        3.0
    """

    def __init__(self, *providers: FrameProvider) -> None:
        self._providers: list[FrameProvider] = []
        # The first providers' `get_planar`, up to one without it (`planar`, at every tick)
        self._planar_readers: tuple[Callable[[str], tuple[float, float, float]], ...] = ()
        for provider in providers:
            self.add_frame_provider(provider)

    def __repr__(self) -> str:
        return f"PoseManager({', '.join(repr(p) for p in self._providers)})"

    @property
    def providers(self) -> tuple[FrameProvider, ...]:
        """The frame providers, in the order they are asked."""
        return tuple(self._providers)

    def add_frame_provider(self, provider: FrameProvider) -> None:
        """Add a frame provider, asked after those already added.

        Raises:
            PoseError: ``provider`` is not a `FrameProvider`, is this manager,
                or was already added.
        """
        candidate: object = provider  # checked at run time too: callers may be untyped
        if not isinstance(candidate, FrameProvider):
            msg = (
                f"{provider!r} is not a FrameProvider: it needs get_transform(frame) "
                "and frames() methods"
            )
            raise PoseError(msg)
        if provider is self:
            msg = "a PoseManager cannot be its own frame provider"
            raise PoseError(msg)
        if any(p is provider for p in self._providers):
            msg = f"{provider!r} is already a frame provider of this PoseManager"
            raise PoseError(msg)
        self._providers.append(provider)
        self._find_planar_readers()
        logger.debug("added frame provider %r", provider)

    def remove_frame_provider(self, provider: FrameProvider) -> None:
        """Remove a frame provider added before.

        Raises:
            PoseError: ``provider`` is not one of this manager's providers.
        """
        for index, known in enumerate(self._providers):
            if known is provider:
                del self._providers[index]
                self._find_planar_readers()
                logger.debug("removed frame provider %r", provider)
                return
        msg = f"{provider!r} is not a frame provider of this PoseManager"
        raise PoseError(msg)

    def frames(self) -> frozenset[str]:
        """Return every frame name known to a provider, and ``map``."""
        known = {MAP}
        for provider in self._providers:
            known.update(provider.frames())
        return frozenset(known)

    def get_transform(self, frame: str) -> Matrix:
        """Return a new 4x4 array, the transform from ``frame`` to ``map``.

        A `PoseManager` is itself a `FrameProvider`.

        Raises:
            UnknownFrameError: No provider knows ``frame`` (the message lists
                the known frames).
            PoseError: A provider returned something that is not 4x4, or
                `FrameTree` chains of several providers form a cycle.
        """
        return self._to_map(frame_name(frame), ())

    def planar(self, frame: str) -> tuple[float, float, float]:
        """Return ``(x, y, yaw)`` of ``frame`` in ``map``: the floor-plane part of `get_transform`.

        The very numbers `get_transform` gives (``x``, ``y`` of its
        translation, ``yaw = atan2(m[1][0], m[0][0])``), without building the
        4x4 array where the provider that knows the frame reads them directly
        (an optional ``get_planar(frame)``, as the simulator's frames have):
        what a recorder sampling the robot's pose at every tick needs.

        Raises:
            UnknownFrameError: No provider knows ``frame``.

        Examples:
            >>> poses = PoseManager()
            >>> tree = FrameTree()
            >>> tree.set_transform("map", "base_link", (1.0, 2.0, 0.0, 0.0, 0.0, 0.5))
            >>> poses.add_frame_provider(tree)
            >>> [round(v, 6) for v in poses.planar("base_link")]
            [1.0, 2.0, 0.5]
        """
        name = frame if type(frame) is str and frame else frame_name(frame)
        for read in self._planar_readers:
            try:
                planar: tuple[float, float, float] = read(name)
            except UnknownFrameError:
                continue
            return planar
        (r0, _, _, x), (r1, _, _, y) = self.get_transform(name)[:2].tolist()
        return (x, y, math.atan2(r1, r0))

    def _find_planar_readers(self) -> None:
        readers = []
        for provider in self._providers:
            read = getattr(provider, "get_planar", None)
            if read is None:
                break  # a provider without it: the general way, in the providers' order
            readers.append(read)
        self._planar_readers = tuple(readers)

    def get(self, raw: PoseLike, *, frame: str | None = None) -> Pose:
        """Read ``raw`` as a `Pose` in a frame that a provider knows.

        Formats (numbers are finite reals, never bools; angles in radians):

        - ``"base_link"``: a frame name, read as the origin of that frame
          (a pose in that frame);
        - ``(x, y, z)``, ``(x, y, z, frame)``: a position, identity
          orientation, frame ``map`` unless given;
        - ``(x, y, z, rx, ry, rz)``, ``(x, y, z, rx, ry, rz, frame)``:
          static-axes sxyz Euler angles;
        - ``(x, y, z, qx, qy, qz, qw)``, ``(x, y, z, qx, qy, qz, qw, frame)``:
          an x-first quaternion (normalised if its norm is within 1e-3 of 1,
          rejected otherwise);
        - a dict (any mapping) with any subset of the keys ``x y z qx qy qz
          qw frame``: missing coordinates are 0; with no quaternion key the
          orientation is the identity, with some the missing components are 0
          (``{"qz": 1.0}`` is a half turn); the frame defaults to ``map``;
          other keys are rejected;
        - a `Pose`, returned as is;
        - a 4x4 rigid matrix (numpy array or nested sequence), the pose of
          a frame's origin in ``frame`` (keyword; default ``map``):
          ``poses.get(matrix, frame="base_link")``.

        Tuples may be lists or 1-D numeric numpy arrays (without a frame).

        Args:
            raw: The value to read.
            frame: The frame of a 4x4 matrix; an error with any other format.

        Raises:
            InvalidPoseError: ``raw`` is none of these, or holds a bad value.
            UnknownFrameError: The pose's frame is unknown to every provider.

        Examples:
            >>> PoseManager().get((1, 2, 0, 0, 0, 0, 1))
            Pose(x=1.0, y=2.0, z=0.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='map')
        """
        pose = parse_pose(raw, frame=frame)
        self._to_map(pose.frame, ())
        return pose

    def inframe(self, pose: PoseLike, frame: str) -> Pose:
        """Return ``pose`` expressed in ``frame``.

        Examples:
            >>> PoseManager().inframe("map", "map")
            Pose(x=0.0, y=0.0, z=0.0, qx=0.0, qy=0.0, qz=0.0, qw=1.0, frame='map')
        """
        source = self.get(pose)
        target_to_map = self._to_map(frame_name(frame), ())
        if source.frame == frame:
            return source
        matrix = invert_rigid(target_to_map) @ self._to_map(source.frame, ()) @ source.matrix()
        return Pose.from_matrix(matrix, frame)

    def distance(self, p1: PoseLike, p2: PoseLike = "base_link") -> float:
        """Return the euclidean distance between two poses' positions (in metres).

        Both are expressed in ``map`` first; the orientations do not matter.
        """
        return float(np.linalg.norm(self._position_in_map(p1) - self._position_in_map(p2)))

    def myself(self) -> Pose:
        """Return the robot's pose: the origin of ``base_link`` expressed in ``map``."""
        return self.inframe("base_link", MAP)

    def pantilt(self, pose: PoseLike, ref: str = "base_link") -> tuple[float, float]:
        """Return the ``(pan, tilt)`` that points ``ref``'s x axis at ``pose``'s position.

        Conventions (ROS REP 103: x forward, y left, z up): ``pan`` is the
        rotation about ``ref``'s z axis, positive to the left
        (counter-clockwise seen from above), in [-π, π]; ``tilt`` is the
        pitch about the panned y axis, **positive looking down** (REP 103's
        positive pitch), in [-π/2, π/2]. Rotating ``ref``'s x axis by yaw
        ``pan`` then pitch ``tilt`` makes it point at the target. A target at
        ``ref``'s origin gives (0, 0); straight above, (0, -π/2).

        Examples:
            >>> PoseManager().pantilt((0, 1, 0), ref="map")  # one metre to the left
            (1.5707963267948966, 0.0)
        """
        target = self.inframe(pose, ref)
        pan = math.atan2(target.y, target.x)
        tilt = math.atan2(-target.z, math.hypot(target.x, target.y))
        return (pan + 0.0, tilt + 0.0)  # + 0.0 turns -0.0 into 0.0

    def euler(self, pose: PoseLike) -> tuple[float, float, float]:
        """Return ``pose``'s orientation as sxyz Euler angles ``(rx, ry, rz)`` in its own frame."""
        return self.get(pose).euler()

    @staticmethod
    def normalize_angle(angle: float) -> float:
        """Return ``angle`` (radians) wrapped into (-π, π]; -π becomes π.

        Examples:
            >>> PoseManager.normalize_angle(-math.pi) == math.pi
            True
        """
        return _math.normalize_angle(angle)

    @staticmethod
    def angular_distance(a1: float, a2: float) -> float:
        """Return the signed angle (radians) turning ``a1`` into ``a2``, in (-π, π].

        Positive means counter-clockwise; the shorter way round is chosen.

        Examples:
            >>> round(PoseManager.angular_distance(3.0, -3.0), 6)  # 2π - 6, across ±π
            0.283185
        """
        return _math.angular_distance(a1, a2)

    @staticmethod
    def isin(point: Pose | Iterable[float], polygon: Iterable[Iterable[float]]) -> bool:
        """Whether a point lies in a 2-D polygon; points on edges and vertices count as in.

        Args:
            point: ``(x, y)``, ``(x, y, z)`` or a `Pose` (z is ignored).
            polygon: Three or more ``(x, y)`` (or ``(x, y, z)``) vertices,
                implicitly closed; concave is fine, self-intersecting ones use
                the even-odd rule. A point within 1e-9 (``EDGE_TOLERANCE``) of
                an edge is on it, hence in. The point and the vertices must be
                in the same frame; no frame conversion is done.

        Raises:
            InvalidPoseError: A malformed point or polygon.

        Examples:
            >>> PoseManager.isin((1, 1), [(0, 0), (2, 0), (2, 2), (0, 2)])
            True
        """
        xy = (point.x, point.y) if isinstance(point, Pose) else _math.point_xy(point)
        return _math.isin(xy, polygon)

    @staticmethod
    def quaternion_from_euler(rx: float, ry: float, rz: float) -> tuple[float, float, float, float]:
        """Return the quaternion of sxyz Euler angles, **x-first**: ``(qx, qy, qz, qw)``.

        Same order as `Pose`'s fields and ROS ``quaternion_from_euler``.

        Examples:
            >>> [round(c, 6) for c in PoseManager.quaternion_from_euler(0, 0, math.pi)]
            [0.0, 0.0, 1.0, 0.0]
        """
        return _math.quaternion_from_euler(rx, ry, rz)

    def _position_in_map(self, raw: PoseLike) -> Vector:
        pose = self.get(raw)
        to_map = self._to_map(pose.frame, ())
        position: Vector = to_map[:3, :3] @ pose.position() + to_map[:3, 3]
        return position

    def _to_map(self, frame: str, via: tuple[str, ...]) -> Matrix:
        if frame == MAP:
            return np.eye(4)
        if frame in via:
            msg = f"frames form a cycle across providers: {' <- '.join((*via, frame))}"
            raise PoseError(msg)
        for provider in self._providers:
            if isinstance(provider, FrameTree):
                if not provider.has(frame):  # (no error built for each frame it lacks)
                    continue
                top, matrix = provider.resolve(frame)
                return matrix if top == MAP else self._to_map(top, (*via, frame)) @ matrix
            try:
                matrix = provider.get_transform(frame)
            except UnknownFrameError:
                continue
            return _checked(provider, frame, matrix)
        raise UnknownFrameError(self._unknown(frame, via))

    def _unknown(self, frame: str, via: tuple[str, ...]) -> str:
        needed = f" (the parent of {via[-1]!r})" if via else ""
        return f"unknown frame {frame!r}{needed}; known frames: {sorted(self.frames())}"


def _checked(provider: FrameProvider, frame: str, matrix: object) -> Matrix:
    try:
        array = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError):
        array = np.empty(0)
    if array.shape != (4, 4):
        msg = (
            f"frame provider {provider!r} returned {_math.show(matrix)} for {frame!r}; "
            "expected a 4x4 transform"
        )
        raise PoseError(msg)
    return array
