"""Resources: immutable, hashable descriptions of what actions compete for.

A resource holds no lock state: the robot's `ResourceManager` does, so two
robots in one process never share locks. Resources compare by value: two
``Resource("wheels")`` objects name the same wheels.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field
from typing import TypeAlias

from .._exceptions import InvalidResourceError

GENERATED_PREFIX = "resource-"
"""How generated names start: ``resource-1``, ``resource-2``, ... (explicit names may not)."""
_GENERATED = re.compile(rf"{GENERATED_PREFIX}[0-9]+")
# Process-wide on purpose: resources are declared at import time, before any robot exists,
# and resources compare by name, so two unnamed ones must never get the same name.
_numbers = itertools.count(1)


@dataclass(frozen=True, slots=True, init=False)
class Resource:
    """A plain resource (the wheels, an arm) that one action at a time may drive.

    Args:
        name: The resource's name, unique on the robot (resources compare by
            name). Without one (pyRobots' ``Resource()``), it gets a generated
            name, ``resource-1``, ``resource-2``, ... in creation order, unique in
            the process; its repr says the name was generated.

    Raises:
        InvalidResourceError: The name is not a non-empty string, or has the
            form of a generated one (``resource-<number>``), which could clash
            with an unnamed resource.

    Examples:
        >>> WHEELS = Resource("wheels")
        >>> WHEELS
        Resource('wheels')
        >>> WHEELS == Resource("wheels")
        True
        >>> Resource().generated, Resource() == Resource()
        (True, False)
    """

    name: str
    generated: bool = field(default=False, init=False, compare=False)
    """Whether the name was generated (the resource was declared without one)."""

    def __init__(self, name: str | None = None) -> None:
        generated = name is None
        if name is None:
            name = f"{GENERATED_PREFIX}{next(_numbers)}"
        else:
            _check_name(name)
            if _GENERATED.fullmatch(name):
                msg = (
                    f"resource names of the form {GENERATED_PREFIX}<number> are kept for "
                    f"generated names, got {name!r}; give another name, e.g. Resource('arm'), "
                    "or none to have one generated"
                )
                raise InvalidResourceError(msg)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "generated", generated)

    @property
    def leaves(self) -> tuple[Resource, ...]:
        """The plain resources this one stands for: itself."""
        return (self,)

    def __repr__(self) -> str:
        if self.generated:
            return f"<Resource {self.name!r} (name generated)>"
        return f"Resource({self.name!r})"


@dataclass(frozen=True, slots=True, init=False)
class CompoundResource:
    """Several resources taken together, all or nothing, atomically.

    Parts may be plain resources or other compounds; the compound stands for
    the set of plain resources (its `leaves`) beneath it.

    Args:
        *parts: The resources it is made of (at least one).
        name: Its name; by default the parts' names joined with ``+``.

    Raises:
        InvalidResourceError: A part is not a resource, there are no parts, the
            compound contains itself (a compound part, at any depth, has its
            name), or a plain part, at any depth, has its name (a name clash).

    Examples:
        >>> L_ARM, R_ARM = Resource("l_arm"), Resource("r_arm")
        >>> ARMS = CompoundResource(L_ARM, R_ARM, name="arms")
        >>> [leaf.name for leaf in ARMS.leaves]
        ['l_arm', 'r_arm']
    """

    parts: tuple[AnyResource, ...]
    name: str
    leaves: tuple[Resource, ...] = field(compare=False, repr=False)
    """The plain resources beneath this compound, each once, in declaration order."""

    def __init__(self, *parts: AnyResource, name: str | None = None) -> None:
        for part in parts:
            check_resource(part, "a part of a CompoundResource")
        if not parts:
            msg = "CompoundResource needs at least one part, got none; e.g. CompoundResource(A, B)"
            raise InvalidResourceError(msg)
        if name is None:
            name = "+".join(part.name for part in parts)
        else:
            _check_name(name)
        _reject_self(name, parts)
        leaves = dict.fromkeys(leaf for part in parts for leaf in part.leaves)
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "leaves", tuple(leaves))

    def __repr__(self) -> str:
        parts = ", ".join(repr(part) for part in self.parts)
        return f"CompoundResource({parts}, name={self.name!r})"


AnyResource: TypeAlias = Resource | CompoundResource
"""A plain or compound resource: what `lock` and the `ResourceManager` accept."""


def check_resource(value: object, what: str) -> AnyResource:
    """Return ``value`` if it is a resource; raise `InvalidResourceError` naming it otherwise."""
    if isinstance(value, Resource | CompoundResource):
        return value
    hint = f"Resource({value!r})" if isinstance(value, str) else "Resource('name')"
    msg = (
        f"{value!r} is not a resource (needed as {what}); "
        f"declare it as {hint} or CompoundResource(...)"
    )
    raise InvalidResourceError(msg)


def _check_name(name: object) -> None:
    if not isinstance(name, str) or not name:
        msg = f"a resource name must be a non-empty string, got {name!r}"
        raise InvalidResourceError(msg)


def _reject_self(name: str, parts: tuple[AnyResource, ...]) -> None:
    """Raise if a part, at any depth, bears the compound's own name (it would contain itself)."""
    stack: list[tuple[AnyResource, tuple[str, ...]]] = [(part, (name,)) for part in parts]
    while stack:
        node, path = stack.pop()
        here = (*path, node.name)
        if node.name == name:
            trail = " > ".join(repr(step) for step in here)
            if isinstance(node, Resource):
                msg = (
                    f"compound resource {name!r} has the name of its part {node!r} ({trail}); "
                    "resources compare by name, so the two would clash: rename one of them"
                )
            else:
                msg = f"compound resource {name!r} contains itself: {trail}; rename one of them"
            raise InvalidResourceError(msg)
        if isinstance(node, CompoundResource):
            stack.extend((part, here) for part in node.parts)
