"""The wheel's build hook: compile the actions core with mypyc, and the pause trampoline in C.

A wheel (``pip install .``, ``uv build``) gets the executive's hot modules
compiled by mypyc and ``_stepped.c`` built, next to their Python sources: an
action costs about 1.3x a bare asyncio task compiled, 1.6x in Python (DESIGN
§10). An editable install is never compiled, so that an edited source is what
runs; the build happens in a temporary directory, never next to the sources.

``PYROBOTS_AIO_BUILD`` chooses: ``auto`` (the default) compiles where it can
and builds a pure-Python wheel, with a warning, where it cannot (no C
compiler); ``compiled`` makes that an error; ``python`` does not compile.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

COMPILED_MODULES = ("_decorator.py", "_executive.py", "_handle.py")  # of pyrobots_aio.actions
C_MODULE = "_stepped.c"
CHOICES = ("auto", "compiled", "python")


class CompileActionsCore(BuildHookInterface):  # type: ignore[type-arg]
    """Build the compiled modules in a temporary directory and add them to the wheel."""

    PLUGIN_NAME = "custom"

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        """Compile for a standard wheel, unless told not to; fall back to Python if allowed."""
        if self.target_name != "wheel" or version != "standard":
            return
        choice = os.environ.get("PYROBOTS_AIO_BUILD", "auto")
        if choice not in CHOICES:
            raise ValueError(f"PYROBOTS_AIO_BUILD={choice!r}: expected one of {', '.join(CHOICES)}")
        if choice == "python":
            return
        self._work = Path(tempfile.mkdtemp(prefix="pyrobots-aio-build-"))
        try:
            built = _compile(Path(self.root), self._work)
        except Exception as exc:
            if choice == "compiled":
                raise
            warnings.warn(
                f"pyrobots_aio: building the pure-Python wheel, the compiled core failed ({exc}); "
                "set PYROBOTS_AIO_BUILD=compiled to see why",
                stacklevel=1,
            )
            return
        self.app.display_info(f"pyrobots_aio: compiled {len(built)} extension modules")
        for path in built:
            build_data["force_include"][str(path)] = path.relative_to(self._work / "lib").as_posix()
        build_data["pure_python"] = False
        build_data["infer_tag"] = True

    def finalize(self, version: str, build_data: dict[str, Any], artifact_path: str) -> None:
        """Remove the temporary build directory once the wheel is written."""
        work = getattr(self, "_work", None)
        if work is not None:
            shutil.rmtree(work, ignore_errors=True)


def _compile(root: Path, work: Path) -> list[Path]:
    """Build the extension modules under ``work / "lib"``; return their paths."""
    from mypyc.build import mypycify
    from setuptools import Distribution, Extension

    actions = Path("src", "pyrobots_aio", "actions")
    here = Path.cwd()
    os.chdir(root)  # mypy names the modules from the paths (src/ is the package root)
    try:
        extensions = mypycify(
            [
                "--ignore-missing-imports",  # the build has mypy, not numpy or anyio
                "--follow-imports=silent",
                *(str(actions / name) for name in COMPILED_MODULES),
            ],
            opt_level="3",
            target_dir=str(work / "mypyc"),
            group_name="pyrobots_aio_actions",
        )
        extensions.append(Extension("pyrobots_aio.actions._stepped", [str(actions / C_MODULE)]))
        distribution = Distribution({"name": "pyrobots-aio", "ext_modules": extensions})
        build_ext: Any = distribution.get_command_obj("build_ext")
        build_ext.build_lib = str(work / "lib")
        build_ext.build_temp = str(work / "temp")
        build_ext.ensure_finalized()
        build_ext.run()
    finally:
        os.chdir(here)
    built = sorted(p for p in (work / "lib").rglob("*") if p.is_file())
    if len(built) != len(COMPILED_MODULES) + 2:  # + mypyc's shared library + the trampoline
        names = ", ".join(p.name for p in built)
        raise RuntimeError(f"expected {len(COMPILED_MODULES) + 2} extension modules, built {names}")
    return built
