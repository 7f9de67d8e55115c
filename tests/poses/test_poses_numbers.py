"""Numbers a pose refuses: NaN, infinities, bools and ints too large for a float."""

from __future__ import annotations

import math

import pytest

from pyrobots_aio import InvalidPoseError, Pose
from pyrobots_aio.poses import PoseManager

HUGE = 10**400
TOO_LARGE = r"an int of about 10\*\*400 \(too large for a float\)"


def test_an_int_too_large_for_a_float_is_an_invalid_pose_naming_it() -> None:
    with pytest.raises(
        InvalidPoseError, match=rf"^x must be a finite real number, got {TOO_LARGE}$"
    ):
        Pose(x=HUGE)  # type: ignore[arg-type]
    with pytest.raises(
        InvalidPoseError, match=rf"^rz must be a finite real number, got {TOO_LARGE}$"
    ):
        Pose.from_euler(0, 0, 0, 0, 0, HUGE)
    with pytest.raises(
        InvalidPoseError, match=rf"^qw must be a finite real number, got {TOO_LARGE}$"
    ):
        Pose.from_wxyz((0, 0, 0), (HUGE, 0, 0, 0))


def test_an_int_too_large_for_a_float_in_any_pose_format_is_refused() -> None:
    poses = PoseManager()
    for value in ([HUGE, 0, 0], {"x": HUGE}):
        with pytest.raises(
            InvalidPoseError, match=rf"x must be a finite real number, got {TOO_LARGE}$"
        ):
            poses.get(value)
    matrix = [[1, 0, 0, HUGE], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    for read in (poses.get, Pose.from_matrix):
        with pytest.raises(InvalidPoseError, match="holds something that is not a real number"):
            read(matrix)


@pytest.mark.parametrize("value", [math.nan, math.inf, True], ids=repr)
def test_nan_infinities_and_bools_stay_refused(value: object) -> None:
    with pytest.raises(InvalidPoseError, match=r"^y must be a finite real number, got "):
        Pose(y=value)  # type: ignore[arg-type]
