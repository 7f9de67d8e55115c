"""Loading a scene with one robot, or with several robots in one world.

One robot: the MJCF file as it is. Several: MuJoCo's model editing
(``MjSpec``) attaches copies of the scene's own robot (the body
``base_link``, with its sensors and actuators) and of its dock (the body
``dock``, with the dock-contact sensor that couples the two), each copy
named with its prefix (``robot2/``, ``robot3/`` ...). So every robot is the
same model, built from the same file, and they all share one physics: they
see and bump into one another.

Where they start: each robot on its own dock, the docks side by side along
the first dock's wall (the world's y axis), `ROBOT_SPACING` apart, in the
order y = 0, +0.5, -0.5, +1.0, -1.0 ... from the scene's dock; each robot
rests on its dock as the scene's keyframe ``home`` puts the first one. In the
shipped arena the first three lanes (y = 0, +-0.5) are clear of obstacles
to the east wall.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .. import ModelLoadError

if TYPE_CHECKING:
    from pathlib import Path
    from types import ModuleType

__all__ = ["MAX_ROBOTS", "ROBOT_SPACING", "lateral_offset", "load_model", "robot_prefix"]

ROBOT_SPACING = 0.5
"""Metres between two neighbouring docks (and robots) of a world of several robots."""

MAX_ROBOTS = 7
"""The most robots one world holds: seven docks fit along the shipped arena's 4 m wall."""

_HOME = "home"
_DOCK_CONTACT = "dock_contact"
_ROBOT_JOINTS = 9  # qpos of one robot: its free joint (7) and its two wheels


def robot_prefix(index: int) -> str:
    """The prefix of robot ``index``'s (from 0) names in the model: none for the first."""
    return f"robot{index + 1}/" if index else ""


def lateral_offset(index: int) -> float:
    """Robot ``index``'s offset along y from the first: 0, +0.5, -0.5, +1.0, -1.0 ..."""
    rank = (index + 1) // 2
    return rank * ROBOT_SPACING * (1 if index % 2 else -1)


def load_model(mujoco: ModuleType, path: Path, robots: int) -> Any:
    """Load the ``MjModel`` of ``path`` with ``robots`` robots in it.

    Raises:
        ModelLoadError: The file does not load, or lacks the robot or the dock to copy.
    """
    if not path.is_file():
        raise ModelLoadError(f"cannot load the MuJoCo model {str(path)!r}: no such file")
    try:
        if robots == 1:
            return mujoco.MjModel.from_xml_path(str(path))
        return _several(mujoco, path, robots)
    except (ValueError, mujoco.FatalError) as err:
        problem = str(err).strip()
        raise ModelLoadError(f"cannot load the MuJoCo model {str(path)!r}: {problem}") from err


def _several(mujoco: ModuleType, path: Path, robots: int) -> Any:
    spec, home = _without_keyframes(mujoco, path)
    if len(home) != _ROBOT_JOINTS:
        msg = (
            f"a world of several robots needs the scene's keyframe {_HOME!r} to place exactly "
            f"the robot's {_ROBOT_JOINTS} joint positions, it has {len(home)}"
        )
        raise ValueError(msg)
    for index in range(1, robots):
        _attach_copy(mujoco, spec, path, index)
        start = list(home[:_ROBOT_JOINTS])
        start[1] += lateral_offset(index)
        home.extend(start)
    spec.add_key(name=_HOME, qpos=home)
    return spec.compile()


def _without_keyframes(mujoco: ModuleType, path: Path) -> tuple[Any, list[float]]:
    """The scene's spec with its keyframes removed (attaching would copy them), and ``home``."""
    spec = mujoco.MjSpec.from_file(str(path))
    home = [float(q) for q in spec.key(_HOME).qpos] if spec.key(_HOME) else []
    for key in list(spec.keys):
        spec.delete(key)
    return spec, home


def _attach_copy(mujoco: ModuleType, spec: Any, path: Path, index: int) -> None:
    """Attach robot ``index``'s robot and dock: copies of the scene's, moved along y."""
    source, _ = _without_keyframes(mujoco, path)
    prefix = robot_prefix(index)
    for body in ("base_link", "dock"):
        part = source.body(body)
        if part is None:
            msg = f"it has no body named {body!r} to copy for robot {index + 1}"
            raise ValueError(msg)
        frame = spec.worldbody.add_frame(pos=[0.0, lateral_offset(index), 0.0])
        frame.attach_body(part, prefix, "")
    _share_assets(spec, prefix)
    # The robot's copy brought the dock-contact sensor along, still measuring against the
    # first dock's pad (the copy of the dock came after it): this robot's dock is its own.
    contact = spec.sensor(f"{prefix}{_DOCK_CONTACT}")
    if contact is not None:
        contact.refname = f"{prefix}{contact.refname}"


def _share_assets(spec: Any, prefix: str) -> None:
    """Give the copies the scene's own materials and textures, not the copies of them.

    Attaching copies every asset of the source; the copied dock would then be
    of material ``robot2/dock``, which `SimWorld.floor_plan` calls its kind.
    """
    for geom in spec.geoms:
        if geom.material.startswith(prefix):
            geom.material = geom.material.removeprefix(prefix)
    for asset in [*spec.materials, *spec.textures]:
        if asset.name.startswith(prefix):
            spec.delete(asset)
