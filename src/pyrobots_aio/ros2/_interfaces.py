"""Interface packages PyPI lacks (``tf2_msgs``, ``irobot_create_msgs``), built from definitions.

The definitions live beside this module (``interfaces/<package>/``): field
names, types, constants and defaults exactly upstream's, so the type hashes
match a real ROS 2 install's. They are built with the ROS 2 toolchain published
on PyPI (the ``ros2-build`` extra) and installed into this environment's own
prefix, where rclpy imports them with nothing set.

- A sourced ROS 2 that provides a package wins: nothing is built for it. So
  does any other install of it, in this prefix too (a conda ROS 2): the
  package.xml carried here has a marker, one without it is another's.
- A stamp per package (a hash of its definitions, of the build file and of the
  interpreter) makes a second build a no-op; a lock file makes two builds at
  once take turns, the second finding the package built.
- What is missing (cmake, the make or ninja its generator runs, a compiler,
  the Python headers, the build wheels) is said in one line, each with its fix.
"""

from __future__ import annotations

import contextlib
import enum
import fcntl
import hashlib
import importlib.util
import logging
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from .._exceptions import InterfaceBuildError

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence

logger = logging.getLogger("pyrobots_aio.ros2")

DEFINITIONS = Path(__file__).parent / "interfaces"
BUILD_FILE = DEFINITIONS / "CMakeLists.txt"
BUILD_EXTRA = "pip install 'pyrobots-aio[ros2-build]'"
TOOLCHAIN = (
    "ament_cmake",
    "ament_cmake_include_directories",
    "ament_cmake_ros_core",
    "rosidl_cmake",
    "rosidl_generator_c",
    "rosidl_generator_py",
    "rosidl_generator_type_description",
    "rosidl_typesupport_c",
    "rosidl_typesupport_fastrtps_c",
    "rosidl_typesupport_introspection_c",
)
"""The ROS 2 packages (``share/<name>``) a build uses, besides the package's own dependencies."""
TOOLCHAIN_MODULES = ("ament_package", "catkin_pkg")
MARKER = "pyrobots_aio's copy of the definitions"
"""In each package.xml carried here: a package.xml without it is another install's."""


class InterfaceOutcome(enum.Enum):
    """What `build_interfaces` did for one package."""

    BUILT = "built"
    UP_TO_DATE = "up to date"
    PROVIDED = "provided by another install"


@dataclass(frozen=True)
class InterfaceBuild:
    """One package's outcome, and where it is (the prefix, or the other install's)."""

    package: str
    outcome: InterfaceOutcome
    where: Path


def interface_packages() -> tuple[str, ...]:
    """The interface packages pyrobots_aio carries the definitions of, sorted.

    Examples:
        >>> interface_packages()
        ('irobot_create_msgs', 'tf2_msgs')
    """
    return tuple(sorted(p.parent.name for p in DEFINITIONS.glob("*/package.xml")))


def build_interfaces(
    packages: Sequence[str] = (), *, prefix: Path | None = None, jobs: int | None = None
) -> list[InterfaceBuild]:
    """Build the interface packages (all of them by default) into ``prefix``, where needed.

    ``prefix`` is this environment's (``sys.prefix``) unless given. A package
    a sourced ROS 2 (or any other install) provides is left to it; one whose
    stamp matches is up to date; the others are built (C type supports only)
    and installed. Blocks while another build holds the prefix's lock.

    Raises:
        InterfaceBuildError: An unknown package, a prefix that cannot be
            written, missing tools (all named, in one line), or a failed step
            (its log named).
        ValueError: ``jobs`` below 1.

    Examples:
        >>> build_interfaces(["tf2_msgs"])  # doctest: +SKIP
        [InterfaceBuild(package='tf2_msgs', outcome=<InterfaceOutcome.BUILT: 'built'>, ...)]
    """
    if jobs is not None and jobs < 1:
        msg = f"jobs must be at least 1, got {jobs!r}"
        raise ValueError(msg)
    prefix = Path(sys.prefix if prefix is None else prefix).resolve()
    wanted = _checked(packages)
    outcomes = {name: _provided(name, prefix) for name in wanted}
    to_build = [name for name in wanted if outcomes[name] is None]
    if to_build:
        with _locked(prefix):
            for name in to_build:
                outcomes[name] = _build_if_stale(name, prefix, jobs)
    return [outcome for outcome in outcomes.values() if outcome is not None]


def missing_tools(packages: Sequence[str] = (), *, prefix: Path | None = None) -> list[str]:
    """What a build of ``packages`` lacks, each with its fix; ``[]`` when nothing is missing."""
    prefix = Path(sys.prefix if prefix is None else prefix).resolve()
    missing = ["" if _which("cmake", prefix) else "no cmake (pip install cmake)"]
    missing += [_missing_build_tool(prefix)]
    missing += [_missing_compiler("CC", ("cc", "gcc"), "C", "gcc")]
    missing += [_missing_compiler("CXX", ("c++", "g++"), "C++", "g++")]
    missing += [_missing_headers(), _missing_toolchain(_checked(packages), prefix)]
    return [line for line in missing if line]


def _checked(packages: Sequence[str]) -> list[str]:
    known = interface_packages()
    unknown = sorted(set(packages) - set(known))
    if unknown:
        msg = f"unknown interface packages {unknown}; pyrobots_aio builds {list(known)}"
        raise InterfaceBuildError(msg)
    return list(dict.fromkeys(packages)) or list(known)


def _provided(name: str, prefix: Path) -> InterfaceBuild | None:
    """Another install's package ``name`` (a sourced ROS 2's, or one in ``prefix`` not ours)."""
    roots = [Path(entry).resolve() for entry in _ament_prefixes()]
    for root in dict.fromkeys([*roots, prefix]):
        manifest = root / "share" / name / "package.xml"
        if manifest.is_file() and MARKER not in manifest.read_text():
            return InterfaceBuild(name, InterfaceOutcome.PROVIDED, root)
    spec = importlib.util.find_spec(name)
    origin = Path(spec.origin).resolve() if spec and spec.origin else None
    ours = (prefix, Path(sys.prefix).resolve())
    if origin is not None and not any(origin.is_relative_to(root) for root in ours):
        return InterfaceBuild(name, InterfaceOutcome.PROVIDED, origin.parent)
    return None


def _ament_prefixes() -> list[str]:
    return [entry for entry in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if entry]


@contextlib.contextmanager
def _locked(prefix: Path) -> Iterator[None]:
    """Hold the prefix's build lock (waiting for another build to finish first)."""
    state = _state_dir(prefix)
    with (state / "build.lock").open("a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            logger.info("another build of the interfaces is running in %s: waiting for it", prefix)
            fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _state_dir(prefix: Path) -> Path:
    state = prefix / "share" / "pyrobots_aio" / "interfaces"
    try:
        state.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        msg = (
            f"cannot build ROS 2 interfaces into {prefix} ({err.strerror}); "
            "run the build from a virtual environment you can write to"
        )
        raise InterfaceBuildError(msg) from err
    return state


def _build_if_stale(name: str, prefix: Path, jobs: int | None) -> InterfaceBuild:
    stamp = _state_dir(prefix) / f"{name}.stamp"
    digest = _digest(name)
    installed = (prefix / "share" / name / "package.xml").is_file()
    if installed and stamp.is_file() and stamp.read_text() == digest:
        return InterfaceBuild(name, InterfaceOutcome.UP_TO_DATE, prefix)
    missing = missing_tools([name], prefix=prefix)
    if missing:
        msg = f"cannot build the ROS 2 interfaces {name}: " + "; ".join(missing)
        raise InterfaceBuildError(msg)
    logger.info("building %s into %s", name, prefix)
    _build(name, prefix, jobs)
    stamp.write_text(digest)
    return InterfaceBuild(name, InterfaceOutcome.BUILT, prefix)


def _digest(name: str) -> str:
    """What a build of ``name`` depends on: its definitions, the build file, the interpreter."""
    sha = hashlib.sha256(f"{sys.executable}\0{sys.version}\0".encode())
    files = sorted(p for p in (DEFINITIONS / name).rglob("*") if p.is_file())
    for path in [BUILD_FILE, *files]:
        sha.update(f"{path.relative_to(DEFINITIONS)}\0".encode() + path.read_bytes() + b"\0")
    return sha.hexdigest()


def _build(name: str, prefix: Path, jobs: int | None) -> None:
    """Configure, build and install ``name`` from a copy of its definitions, logging to a file.

    The install goes to a staging folder first, then each file is renamed
    into place: a program running on the old build keeps its libraries.
    """
    state = _state_dir(prefix)
    cmake = str(_which("cmake", prefix))
    with tempfile.TemporaryDirectory(prefix=f"{name}-", dir=state) as tmp:
        source, build, stage = Path(tmp) / name, Path(tmp) / "build", Path(tmp) / "stage"
        shutil.copytree(DEFINITIONS / name, source)
        shutil.copy(BUILD_FILE, source / "CMakeLists.txt")
        configure = [
            *(cmake, "-S", str(source), "-B", str(build)),
            *(f"-DCMAKE_INSTALL_PREFIX={prefix}", f"-DCMAKE_PREFIX_PATH={prefix}"),
            *(f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF"),
            "-DCMAKE_BUILD_TYPE=Release",
        ]
        parallel = str(jobs or os.cpu_count() or 1)
        env = {**os.environ, "AMENT_PREFIX_PATH": str(prefix)}
        with (state / f"{name}.log").open("w") as log:
            _run(name, "configure", configure, log, env)
            _run(name, "build", [cmake, "--build", str(build), "--parallel", parallel], log, env)
            install = [cmake, "--install", str(build)]
            _run(name, "install", install, log, {**env, "DESTDIR": str(stage)})
        _move_into(stage / prefix.relative_to(prefix.anchor), prefix)


def _run(name: str, step: str, command: list[str], log: TextIO, env: dict[str, str]) -> None:
    log.write(f"$ {' '.join(command)}\n")
    log.flush()
    ran = subprocess.run(command, check=False, stdout=log, stderr=log, env=env)
    if code := ran.returncode:
        msg = f"building {name} failed at its {step} step (exit {code}); the log: {log.name}"
        raise InterfaceBuildError(msg)


def _move_into(staged: Path, prefix: Path) -> None:
    """Rename every file under ``staged`` to the same place under ``prefix``."""
    for folder, _, files in os.walk(staged):
        target = prefix / Path(folder).relative_to(staged)
        target.mkdir(parents=True, exist_ok=True)
        for file in files:
            os.replace(Path(folder) / file, target / file)


def _which(program: str, prefix: Path) -> Path | None:
    """``program`` in ``prefix``'s ``bin`` (where the cmake wheel puts it), else on PATH."""
    path = os.pathsep.join([str(prefix / "bin"), os.environ.get("PATH", "")])
    found = shutil.which(program, path=path)
    return Path(found) if found else None


def _missing_build_tool(prefix: Path) -> str:
    """The program cmake's generator runs (``CMAKE_GENERATOR``, else Unix Makefiles), if absent.

    Without it, cmake's configure step fails, and only its log would say why.
    """
    generator = os.environ.get("CMAKE_GENERATOR") or "Unix Makefiles"
    if "Ninja" in generator:
        program, fix = "ninja", "pip install ninja"
    elif "Makefiles" in generator:
        program, fix = "make", "apt-get install make"
    else:  # another generator (an IDE's): cmake's own message is the best there is
        return ""
    if _which(program, prefix):
        return ""
    return f"no {program}, which cmake's {generator} generator runs ({fix})"


def _missing_compiler(variable: str, programs: Sequence[str], language: str, package: str) -> str:
    chosen = os.environ.get(variable)
    if chosen and shutil.which(chosen.split()[0]):
        return ""
    if not chosen and any(shutil.which(program) for program in programs):
        return ""
    named = f"{variable}={chosen!r} is not a program" if chosen else f"no {language} compiler"
    return f"{named} (apt-get install {package})"


def _missing_headers() -> str:
    include = Path(sysconfig.get_paths()["include"])
    if (include / "Python.h").is_file():
        return ""
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    return f"no Python headers (no {include / 'Python.h'}: apt-get install python{version}-dev)"


def _missing_toolchain(packages: Sequence[str], prefix: Path) -> str:
    needed = [*TOOLCHAIN, *(dep for name in packages for dep in _dependencies(name))]
    share = prefix / "share"
    absent = [n for n in dict.fromkeys(needed) if not (share / n / "package.xml").is_file()]
    absent += [m for m in TOOLCHAIN_MODULES if importlib.util.find_spec(m) is None]
    return f"no ROS 2 build tools {absent} ({BUILD_EXTRA})" if absent else ""


def _dependencies(name: str) -> list[str]:
    """The build dependencies ``name``'s package.xml names (``depend`` and ``build_depend``)."""
    root = ET.parse(DEFINITIONS / name / "package.xml").getroot()
    return [node.text or "" for tag in ("depend", "build_depend") for node in root.iter(tag)]
