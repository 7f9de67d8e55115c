"""One owner for an action's state (STYLE 16a): only ``actions/_handle.py`` writes a handle.

The executive, the pause trampoline, the resources layer and the robot ask a
handle (its methods and properties) and never write its fields. An AST scan
of the package finds every write of an attribute named like one of
`ActionHandle`'s fields (its ``__slots__``) on something other than ``self``:
an assignment, an augmented or annotated one, a ``del``, a ``setattr`` with a
constant name. A name annotated in its function with another type is not a
handle (``act: Action[...]``, whose ``name`` is the action's own); anything
else is taken for one.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

import pyrobots_aio
from pyrobots_aio.actions import ActionHandle

PACKAGE = Path(pyrobots_aio.__file__).parent
OWNER = Path("actions", "_handle.py")
FIELDS = frozenset(ActionHandle.__slots__) - {"__weakref__"}
MODULES = sorted(p for p in PACKAGE.rglob("*.py") if p.relative_to(PACKAGE) != OWNER)


def _annotations(function: ast.FunctionDef | ast.AsyncFunctionDef) -> dict[str, str]:
    """What each name is annotated as in ``function``: its parameters, its annotated assignments."""
    args = function.args
    every = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
    found = {a.arg: ast.unparse(a.annotation) for a in every if a is not None and a.annotation}
    for node in ast.walk(function):
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            found[node.target.id] = ast.unparse(node.annotation)
    return found


def _targets(node: ast.AST) -> Iterator[tuple[ast.expr, str]]:
    """What ``node`` writes: ``(receiver, attribute)`` for each attribute it sets or deletes."""
    if isinstance(node, ast.Assign | ast.Delete):
        stack = list(node.targets)
    elif isinstance(node, ast.AugAssign | ast.AnnAssign):
        stack = [node.target]
    elif (
        isinstance(node, ast.Call)
        and ast.unparse(node.func) in {"setattr", "delattr", "object.__setattr__"}
        and len(node.args) >= 2  # the object and the attribute's name
        and isinstance(node.args[1], ast.Constant)
        and isinstance(node.args[1].value, str)
    ):
        yield node.args[0], node.args[1].value
        return
    else:
        return
    while stack:
        target = stack.pop()
        if isinstance(target, ast.Tuple | ast.List):
            stack.extend(target.elts)
        elif isinstance(target, ast.Starred):
            stack.append(target.value)
        elif isinstance(target, ast.Attribute):
            yield target.value, target.attr


def _handle_writes(source: str) -> list[str]:
    """Each write of a handle field in ``source`` on something but ``self``, as ``line: code``."""
    found = set()

    def visit(node: ast.AST, known: dict[str, str]) -> None:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            known = known | _annotations(node)
        for receiver, attribute in _targets(node):
            if attribute in FIELDS and not _not_a_handle(receiver, known):
                found.add(f"{node.lineno}: {ast.unparse(node).splitlines()[0]}")
        for child in ast.iter_child_nodes(node):
            visit(child, known)

    visit(ast.parse(source), {})
    return sorted(found)


def _not_a_handle(receiver: ast.expr, known: dict[str, str]) -> bool:
    if not isinstance(receiver, ast.Name):
        return False
    if receiver.id == "self":
        return True
    annotation = known.get(receiver.id)
    return annotation is not None and "ActionHandle" not in annotation


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_only_the_handle_writes_its_fields(path: Path) -> None:
    writes = _handle_writes(path.read_text())
    assert not writes, f"{path.relative_to(PACKAGE)} writes an ActionHandle's fields: {writes}"


def test_the_fields_are_the_handles_slots() -> None:
    assert {"_cancel", "_freeze", "_phase", "_outcome", "parent", "started_at"} <= FIELDS


def test_the_scan_finds_writes_of_handle_fields() -> None:
    # What the executive, the pause layer and the resources layer once wrote themselves.
    source = (
        "def cancel(handle, reason, by):\n"
        "    handle._cancel = (reason, by)\n"
        "    handle._phase, node._outcome = 1, 2\n"
        "    handle.started_at += 1.0\n"
        "    del handle._freeze\n"
        "    setattr(handle, '_task', None)\n"
        "def name(act: Action[Robot, Any, Any], h: ActionHandle[Any]) -> None:\n"
        "    act.name = 'goal'\n"
        "    h.name = 'renamed'\n"
        "    self.name = 'mine'\n"
        "    grant.held = ('wheels',)\n"
    )
    assert _handle_writes(source) == [
        "2: handle._cancel = (reason, by)",
        "3: handle._phase, node._outcome = (1, 2)",
        "4: handle.started_at += 1.0",
        "5: del handle._freeze",
        "6: setattr(handle, '_task', None)",
        "9: h.name = 'renamed'",
    ]
