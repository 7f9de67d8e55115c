"""Which build of the actions core runs: ``"compiled"`` or ``"python"``.

An install built from a wheel where a C compiler was at hand runs the
executive's hot modules (`_handle`, `_executive`, `_decorator`) compiled by
mypyc, and the pause trampoline in C (``_stepped.c``); an editable install, or
one built with no compiler, runs the same modules as Python. Both builds pass
the same test suite (``nox -s tests`` and ``nox -s compiled``).

What the compiled build lacks: frames (a compiled function has none, so log
records and stacks name the nearest Python frame), method and function
docstrings (the class and module ones are put back here from the sources,
which ship beside the compiled modules), and weak references to `Action`.
"""

from __future__ import annotations

import ast
from importlib.machinery import EXTENSION_SUFFIXES
from pathlib import Path
from types import ModuleType
from typing import Final, Literal

from . import _decorator, _executive, _handle

_COMPILED = tuple(
    module.__name__
    for module in (_decorator, _executive, _handle)
    if (module.__file__ or "").endswith(tuple(EXTENSION_SUFFIXES))
)

if _COMPILED and len(_COMPILED) != 3:  # a stale extension module next to edited sources
    raise ImportError(
        f"pyrobots_aio is half compiled ({', '.join(_COMPILED)} only): "
        "reinstall it (pip install --force-reinstall pyrobots-aio), or delete the stray .so files"
    )

BUILD: Final[Literal["compiled", "python"]] = "compiled" if _COMPILED else "python"


def restore_docstrings(module: ModuleType) -> None:
    """Give a compiled ``module`` and its classes the docstrings of its source, where it ships."""
    name = module.__name__.rpartition(".")[2]
    source = Path(module.__file__ or "").with_name(f"{name}.py")
    if not source.is_file():
        return
    tree = ast.parse(source.read_text(encoding="utf-8"))
    module.__doc__ = ast.get_docstring(tree, clean=False)
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            cls = getattr(module, node.name, None)
            if isinstance(cls, type) and not cls.__doc__:
                cls.__doc__ = ast.get_docstring(node, clean=False)


if _COMPILED:
    from ._stepped import seal_weakrefs

    for _cls in (_decorator.Action, _decorator.BoundAction, _handle.ActionHandle):
        seal_weakrefs(_cls)
    for _module in (_decorator, _executive, _handle):
        restore_docstrings(_module)
