"""Reading the raw pose formats of DESIGN.md §6 into a `Pose`.

Pure parsing: whether the frame exists is the `PoseManager`'s business.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, TypeAlias, TypeGuard

import numpy as np
from numpy.typing import NDArray

from .._exceptions import InvalidPoseError
from ._math import Matrix, finite_float, show
from ._pose import Pose, frame_name

PoseLike: TypeAlias = (
    Pose
    | str
    | Sequence[float | str]
    | Sequence[Sequence[float]]
    | Mapping[str, float | str]
    | NDArray[Any]
)
"""Anything `PoseManager.get` reads as a pose."""

FORMATS = (
    "a frame name, (x, y, z[, frame]), (x, y, z, rx, ry, rz[, frame]) with sxyz Euler angles, "
    "(x, y, z, qx, qy, qz, qw[, frame]), a dict with keys among x y z qx qy qz qw frame, "
    "a Pose, or a 4x4 rigid matrix (with frame=...)"
)
"""What `PoseManager.get` accepts, for error messages."""

_POSITION = ("x", "y", "z")
_QUATERNION = ("qx", "qy", "qz", "qw")
_EULER = ("rx", "ry", "rz")
_DICT_KEYS = frozenset((*_POSITION, *_QUATERNION, "frame"))
_BY_COUNT = {3: _POSITION, 6: _POSITION + _EULER, 7: _POSITION + _QUATERNION}


class _ShapeError(InvalidPoseError):
    """The raw value is none of the formats; the message gets the list of formats."""


def parse_pose(raw: object, *, frame: str | None = None, default_frame: str = "map") -> Pose:
    """Read ``raw`` as a `Pose` (see `PoseManager.get` for the formats).

    Args:
        raw: The value to read.
        frame: The frame of a 4x4 matrix; only allowed with a matrix.
        default_frame: The frame of formats that name none.

    Raises:
        InvalidPoseError: ``raw`` is none of the formats, or holds a bad value.
    """
    if _looks_like_matrix(raw):
        return Pose.from_matrix(raw, default_frame if frame is None else frame)
    try:
        return _parse(raw, frame, default_frame)
    except _ShapeError as exc:
        msg = f"cannot read {show(raw)} as a pose: {exc}; expected {FORMATS}"
        raise InvalidPoseError(msg) from None
    except InvalidPoseError as exc:
        msg = f"cannot read {show(raw)} as a pose: {exc}"
        raise InvalidPoseError(msg) from None


def _looks_like_matrix(raw: object) -> TypeGuard[Matrix | Sequence[Sequence[float]]]:
    """A 2-D array, or a sequence of rows only: 4 rows, or rows of 4 (so a bad row is named).

    Anything else, such as ``((x, y, z), (qx, qy, qz, qw))`` or ``(x, y, z, b"map")``,
    is read as one of the other formats, whose error lists them all.
    """
    if isinstance(raw, np.ndarray):
        return raw.ndim == 2
    if not _is_row(raw) or not all(_is_row(row) for row in raw):
        return False
    return len(raw) == 4 or (len(raw) > 0 and all(len(row) == 4 for row in raw))


def _is_row(item: object) -> TypeGuard[Sequence[Any] | NDArray[Any]]:
    """A numpy array of numbers or a sequence other than text (a str or bytes is no row)."""
    if isinstance(item, np.ndarray):
        return item.ndim >= 1
    return isinstance(item, Sequence) and not isinstance(item, str | bytes)


def _parse(raw: object, frame: str | None, default_frame: str) -> Pose:
    if frame is not None:
        msg = f"frame={frame!r} is only for a 4x4 matrix; put the frame inside the pose instead"
        raise _ShapeError(msg)
    if isinstance(raw, Pose):
        return raw
    if isinstance(raw, str):
        return Pose(frame=frame_name(raw, "a frame name"))
    if isinstance(raw, Mapping):
        return _from_mapping(raw, default_frame)
    if isinstance(raw, np.ndarray):
        if raw.ndim != 1 or raw.dtype.kind not in "iuf":
            msg = (
                "a numpy array must be a 1-D numeric pose or a 4x4 matrix, "
                f"got {raw.ndim}-D of dtype {raw.dtype}"
            )
            raise _ShapeError(msg)
        return _from_sequence(raw.tolist(), default_frame)
    if isinstance(raw, Sequence) and not isinstance(raw, bytes):
        return _from_sequence(raw, default_frame)
    msg = f"a {type(raw).__name__} is not a pose"
    raise _ShapeError(msg)


def _from_sequence(items: Sequence[object], default_frame: str) -> Pose:
    has_frame = len(items) > 0 and isinstance(items[-1], str)
    numbers = items[:-1] if has_frame else items
    names = _BY_COUNT.get(len(numbers))
    if names is None:
        msg = f"a sequence of {len(items)} item{'' if len(items) == 1 else 's'} is not a pose"
        raise _ShapeError(msg)
    frame = str(items[-1]) if has_frame else default_frame
    values = [finite_float(name, value) for name, value in zip(names, numbers, strict=True)]
    if len(values) == 3:
        x, y, z = values
        return Pose(x, y, z, frame=frame)
    if len(values) == 6:
        x, y, z, rx, ry, rz = values
        return Pose.from_euler(x, y, z, rx, ry, rz, frame)
    x, y, z, qx, qy, qz, qw = values
    return Pose(x, y, z, qx, qy, qz, qw, frame)


def _from_mapping(raw: Mapping[object, object], default_frame: str) -> Pose:
    unknown = sorted(repr(key) for key in raw if key not in _DICT_KEYS)
    if unknown:
        msg = f"unknown key(s) {', '.join(unknown)} in a pose dict"
        raise _ShapeError(msg)
    x, y, z = (finite_float(key, raw.get(key, 0.0)) for key in _POSITION)
    qx, qy, qz, qw = 0.0, 0.0, 0.0, 1.0
    if any(key in raw for key in _QUATERNION):
        # Any quaternion key given: the missing components are 0, so {"qz": 1} is a half turn.
        qx, qy, qz, qw = (finite_float(key, raw.get(key, 0.0)) for key in _QUATERNION)
    frame = frame_name(raw.get("frame", default_frame))
    return Pose(x, y, z, qx, qy, qz, qw, frame)
