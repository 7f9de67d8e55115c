"""tf over ROS 2: the transforms a base broadcasts on ``tf`` and ``tf_static``, both ways.

`TfBuffer` is a robot's tf listener: it keeps the latest transform of each
edge heard, in a `pyrobots_aio.poses.FrameTree`, so ``robot.poses`` places
the frames a driver broadcasts (a base's sensor frames) as the simulator's
provider places its own. Frames the robot places itself (``odom``,
``base_link`` from its odometry topic) are not taken from tf: the motion
layer and ``robot.poses`` then read one pose, not two that lag each other.
Only the latest transform is kept (``robot.poses`` asks about now, not about
a past stamp), so there is no interpolation and no history to bound.

`TfBroadcaster` is the publishing end (``sim-node``): ``tf`` with the
default QoS, ``tf_static`` latched (transient local), as tf2's broadcasters do.

``tf2_msgs`` has no wheel on PyPI: it is built with ``pyrobots-aio ros2
interfaces build tf2_msgs`` (or comes with a sourced ROS 2).
"""

from __future__ import annotations

import asyncio
import importlib
import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np
import transforms3d.quaternions as t3d_quaternions

from .._exceptions import PoseError, Ros2UnavailableError, UnknownFrameError
from ..poses import FrameTree
from ._rclpy import rclpy_module

if TYPE_CHECKING:
    from collections.abc import Collection, Iterable

    from ..motion import Pose2D
    from ..poses import Matrix
    from ._node import Ros2Node
    from ._topics import Ros2Publisher

_log = logging.getLogger("pyrobots_aio.ros2")

TF, TF_STATIC = "tf", "tf_static"
"""The topics' names, relative: under a namespace they are ``<namespace>/tf``, as a
namespaced Create 3 (or Nav2 robot) has them; at the root they are ``/tf`` and ``/tf_static``."""
BUILD_TF = "pyrobots-aio ros2 interfaces build tf2_msgs"
_DEPTH = 100  # tf2's listeners' and broadcasters' history depth


def tf_message_class() -> type:
    """``tf2_msgs.msg.TFMessage`` (its type support loaded).

    Raises:
        Ros2UnavailableError: ``tf2_msgs`` cannot be imported; the message says how to build it.
    """
    rclpy_module()
    try:
        cls: type = importlib.import_module("tf2_msgs.msg").TFMessage
    except ImportError as err:
        msg = (
            f"tf needs the tf2_msgs interfaces, which cannot be imported ({err}); "
            f"build them with: {BUILD_TF}"
        )
        raise Ros2UnavailableError(msg) from err
    rclpy_module("rclpy.type_support").check_is_valid_msg_type(cls)
    return cls


def tf_available() -> bool:
    """Whether ``tf2_msgs`` can be imported (built, or from a sourced ROS 2)."""
    try:
        tf_message_class()
    except Ros2UnavailableError:
        return False
    return True


def tf_qos(*, static: bool) -> Any:
    """tf2's QoS: reliable, depth 100; ``tf_static`` transient local, so late joiners get it."""
    qos = rclpy_module("rclpy.qos")
    durability = qos.DurabilityPolicy.TRANSIENT_LOCAL if static else qos.DurabilityPolicy.VOLATILE
    return qos.QoSProfile(
        depth=_DEPTH, reliability=qos.ReliabilityPolicy.RELIABLE, durability=durability
    )


def transform_matrix(transform: Any) -> Matrix:
    """The 4x4 matrix of a ``geometry_msgs/Transform`` (its quaternion normalised)."""
    t, q = transform.translation, transform.rotation
    wxyz = np.array([q.w, q.x, q.y, q.z], dtype=np.float64)
    norm = float(np.linalg.norm(wxyz))
    if not math.isfinite(norm) or norm == 0.0 or not all(map(math.isfinite, (t.x, t.y, t.z))):
        msg = f"not a rigid transform: translation {(t.x, t.y, t.z)}, rotation {tuple(wxyz)}"
        raise ValueError(msg)
    matrix = np.eye(4)
    matrix[:3, :3] = t3d_quaternions.quat2mat(wxyz / norm)
    matrix[:3, 3] = (t.x, t.y, t.z)
    return matrix


def planar_matrix(x: float, y: float, yaw: float) -> Matrix:
    """The 4x4 matrix of a pose in the floor plane, ``(x, y, yaw)``."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _frame(name: str) -> str:
    """A tf frame id as tf2 reads it: without a leading slash."""
    return name.lstrip("/")


class TfBuffer:
    """The latest transform of each tf edge heard, as a `FrameTree`; waitable per frame.

    Args:
        placed: Frames placed by their owner, not by tf (their edges are ignored).
    """

    def __init__(self, placed: Collection[str]) -> None:
        self.tree = FrameTree()
        self._placed = frozenset(placed)
        self._roots = self._placed | {"map"}
        self._refused: set[tuple[str, str]] = set()
        self._waiters: list[tuple[tuple[str, ...], asyncio.Future[None]]] = []

    def receive(self, message: Any) -> None:
        """Take a ``tf2_msgs/TFMessage`` (on the loop): each edge's transform replaces the last."""
        for stamped in message.transforms:
            self._take(_frame(stamped.header.frame_id), _frame(stamped.child_frame_id), stamped)
        if self._waiters:
            self._wake()

    def _take(self, parent: str, child: str, stamped: Any) -> None:
        if child in self._placed:
            return
        try:
            matrix = transform_matrix(stamped.transform)
            if self.tree.has(child) and child != "map" and self.tree.parent(child) != parent:
                self.tree.remove_transform(child)  # tf lets a frame change parents
            self.tree.set_transform(parent, child, matrix)
        except (PoseError, ValueError) as err:
            if (parent, child) not in self._refused:  # once per edge: tf repeats at its rate
                self._refused.add((parent, child))
                _log.warning("tf: refused the transform %s -> %s: %s", parent, child, err)

    def places(self, frame: str) -> bool:
        """Whether tf has a chain from ``frame`` up to a frame the robot places (or ``map``)."""
        return self.tree.has(frame) and self.tree.resolve(frame)[0] in self._roots

    def resolve(self, frame: str) -> tuple[str, Matrix]:
        """The top of ``frame``'s chain and the transform to it (`FrameTree.resolve`).

        Raises:
            UnknownFrameError: tf has not placed ``frame``.
        """
        return self.tree.resolve(frame)

    def frames(self) -> frozenset[str]:
        """Every frame tf placed (not ``map``)."""
        return self.tree.frames() - {"map"}

    async def wait_for_frames(self, *frames: str) -> None:
        """Return once tf places every one of ``frames`` (wrap it in a timeout).

        Examples:
            >>> await robot.tf.wait_for_frames("ir_left", "bumper_left")  # doctest: +SKIP
        """
        if all(self.places(f) for f in frames):
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        entry = (frames, future)
        self._waiters.append(entry)
        try:
            await future
        finally:
            self._waiters.remove(entry)

    def _wake(self) -> None:
        for frames, future in self._waiters:
            if not future.done() and all(self.places(f) for f in frames):
                future.set_result(None)

    def __repr__(self) -> str:
        return f"<TfBuffer {sorted(self.frames())}>"


def place_through_tf(tf: TfBuffer | None, frame: str, place: Any, known: Iterable[str]) -> Matrix:
    """``frame`` placed in ``map`` through tf, its chain's top placed by ``place(top)``.

    Raises:
        UnknownFrameError: tf does not place ``frame`` (``known`` listed).
    """
    if tf is None or not tf.tree.has(frame):
        msg = f"unknown frame {frame!r}; known frames: {sorted(known)}"
        raise UnknownFrameError(msg)
    top, matrix = tf.resolve(frame)
    if top == "map":
        return matrix
    placed: Matrix = place(top) @ matrix
    return placed


class TfBroadcaster:
    """Publishes transforms on ``tf`` and, once, the static ones on ``tf_static``.

    Args:
        node: The node publishing them (running).
    """

    def __init__(self, node: Ros2Node) -> None:
        tf_type = tf_message_class()
        self._message = tf_type
        self._stamped = rclpy_module("geometry_msgs.msg").TransformStamped
        self._tf: Ros2Publisher[Any] = node.publisher(TF, tf_type, qos=tf_qos(static=False))
        self._static: Ros2Publisher[Any] = node.publisher(
            TF_STATIC, tf_type, qos=tf_qos(static=True)
        )

    def send(self, edges: Iterable[tuple[str, str, Matrix]], stamp: Any) -> None:
        """Publish ``(parent, child, matrix)`` edges on ``tf``, stamped ``stamp``."""
        self._tf.publish(self._encode(edges, stamp))

    def send_odometry(self, pose: Pose2D, stamp: Any) -> None:
        """Publish ``odom -> base_link`` at the odometry pose ``(x, y, yaw)`` on ``tf``."""
        self.send((("odom", "base_link", planar_matrix(*pose)),), stamp)

    def send_static(self, edges: Iterable[tuple[str, str, Matrix]], stamp: Any) -> None:
        """Publish every static edge on ``tf_static``, in one latched message."""
        self._static.publish(self._encode(edges, stamp))

    def _encode(self, edges: Iterable[tuple[str, str, Matrix]], stamp: Any) -> Any:
        return self._message(transforms=[self._edge(*edge, stamp) for edge in edges])

    def _edge(self, parent: str, child: str, matrix: Matrix, stamp: Any) -> Any:
        stamped = self._stamped()
        stamped.header.stamp, stamped.header.frame_id, stamped.child_frame_id = (
            stamp,
            parent,
            child,
        )
        t, r = stamped.transform.translation, stamped.transform.rotation
        t.x, t.y, t.z = (float(v) for v in matrix[:3, 3])
        r.w, r.x, r.y, r.z = (float(v) for v in t3d_quaternions.mat2quat(matrix[:3, :3]))
        return stamped
