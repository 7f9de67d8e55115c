"""``lock``: take resources for an action, as a decorator or as an ``async with`` block.

The lock state is the robot's (``robot.resources``): the decorator finds it on
its first argument (the robot), the context manager through the current
action. As a decorator, the resources are held until the action is *done*
(its cleanup and children included): they are released by a finalizer of its
handle, so a preempting action gets them only once the preempted one has
stopped driving them. Stacked ``@lock`` decorators make one atomic request.

A ``@lock`` wrapper is the action's body when the action's function is it, or
wraps it through ``__wrapped__`` (decorators that use `functools.wraps`, so
``@action @my_decorator @lock(R)`` still holds until the action is done);
anything else awaiting it is a locked helper, holding for the call only.
"""

from __future__ import annotations

import functools
import inspect
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NoReturn, ParamSpec, TypeVar, overload

from .._exceptions import InvalidResourceError, LockUsageError
from ..resources import ResourceManager
from ..resources._grant import Options, Preempt, check_options
from ..resources._resource import check_resource
from ._decorator import Action
from ._handle import current_action

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

    from ..resources import AnyResource, Grant
    from ._handle import ActionHandle

P = ParamSpec("P")
T = TypeVar("T")
R = TypeVar("R")

_Options = Options
_MARK = "__pyrobots_lock__"


@dataclass(frozen=True, slots=True)
class _Locked:
    """What a ``@lock`` wrapper wraps, so that stacked locks merge into one request."""

    fn: Callable[..., Coroutine[Any, Any, Any]]
    resources: tuple[AnyResource, ...]
    options: _Options


class Lock:
    """Resources to take, with how to take them; made by `lock`.

    Use it as a decorator (above or below ``@action``) or as an async context
    manager inside an action.
    """

    __slots__ = ("_grants", "preempt", "priority", "resource", "wait")

    def __init__(self, resource: AnyResource, wait: bool, priority: int, preempt: Preempt) -> None:
        self.resource = check_resource(resource, "the resource to lock")
        check_options(wait, priority, preempt)
        self.wait = wait
        self.priority = priority
        self.preempt: Preempt = preempt
        self._grants: dict[ActionHandle[Any], list[Grant[ActionHandle[Any]]]] = {}

    @property
    def _options(self) -> _Options:
        return (self.wait, self.priority, self.preempt)

    # -- as a decorator ---------------------------------------------------

    @overload
    def __call__(self, target: Action[R, P, T]) -> Action[R, P, T]: ...

    @overload
    def __call__(
        self, target: Callable[P, Coroutine[Any, Any, T]]
    ) -> Callable[P, Coroutine[Any, Any, T]]: ...

    def __call__(self, target: Any) -> Any:
        if isinstance(target, Action):
            return Action(self._decorate(target.fn), target.hooks)
        if inspect.iscoroutinefunction(target):
            return self._decorate(target)
        msg = f"{self!r} decorates an 'async def' or an @action, got {target!r}"
        raise LockUsageError(msg)

    def _decorate(
        self, fn: Callable[..., Coroutine[Any, Any, Any]]
    ) -> Callable[..., Coroutine[Any, Any, Any]]:
        inner: _Locked | None = getattr(fn, _MARK, None)
        if inner is None:
            return _wrap(_Locked(fn, (self.resource,), self._options))
        if inner.options != self._options:
            names = ", ".join(repr(r.name) for r in inner.resources)
            msg = (
                f"stacked @lock decorators on {fn.__name__!r} take their resources in one "
                f"atomic request, so they need the same wait/priority/preempt: {self!r} "
                f"differs from the lock on {names}; give them the same options"
            )
            raise LockUsageError(msg)
        return _wrap(_Locked(inner.fn, (self.resource, *inner.resources), self._options))

    # -- as a context manager ---------------------------------------------

    def __enter__(self) -> NoReturn:
        self._not_sync()

    def __exit__(self, *exc_info: object) -> NoReturn:
        self._not_sync()

    def _not_sync(self) -> NoReturn:
        msg = (
            f"'with {self!r}' cannot wait for the resource without blocking the loop; "
            f"write 'async with {self!r}:' inside an @action body"
        )
        raise LockUsageError(msg)

    async def __aenter__(self) -> Grant[ActionHandle[Any]]:
        handle = current_action.get()
        if handle is None:
            msg = (
                f"'async with {self!r}' needs a running action to hold the resource; "
                "use it inside an @action body"
            )
            raise LockUsageError(msg)
        manager = _manager_of(handle._executive.owner, repr(self))
        grant = await manager.acquire(
            handle, self.resource, wait=self.wait, priority=self.priority, preempt=self.preempt
        )
        self._grants.setdefault(handle, []).append(grant)
        return grant

    async def __aexit__(self, *exc_info: object) -> None:
        handle = current_action.get()
        stack = self._grants.get(handle) if handle is not None else None
        if not stack:
            msg = f"{self!r} exited without being entered in this action"
            raise LockUsageError(msg)
        grant = stack.pop()
        if not stack:
            del self._grants[grant.owner]
        grant.release()

    def __repr__(self) -> str:
        return (
            f"lock({self.resource!r}, wait={self.wait}, priority={self.priority}, "
            f"preempt={self.preempt!r})"
        )


def lock(
    resource: AnyResource, wait: bool = True, priority: int = 0, preempt: Preempt = False
) -> Lock:
    """Take ``resource`` for an action: a decorator, or an async context manager.

    As a decorator (above or below ``@action``, stackable) the resource is
    taken before the body runs and held until the action is done, cleanup
    included. As ``async with lock(res):`` inside an action, it is held for
    the block. A compound resource is taken all or nothing; an action may
    take what one of its ancestors holds without waiting.

    Args:
        resource: A `Resource` or `CompoundResource`.
        wait: If False and the resource is busy, the action does not run: its
            outcome is ``SKIPPED`` and awaiting it raises `ActionSkipped`.
        priority: Waiters are served by priority (higher first), then in order.
        preempt: If every action in the way has a lower priority, cancel them
            and take the resource once their cleanup is done, after any earlier
            queued request of equal or higher priority. With ``wait=False`` it
            still waits for that cleanup, but is skipped without cancelling
            anyone if an earlier queued request would be served first.
            ``preempt="suspend"``: suspend them instead of cancelling them
            (their subtrees freeze as if paused, their pause hooks park their
            actuators) and take the resource at once; when this action lets
            go of it, they get it back before anyone waiting and resume where
            they stood (a motion goes on with its remaining distance). With
            ``wait=False`` it is skipped if it cannot suspend at once.

    Note:
        A decorator between ``@action`` and ``@lock`` must keep ``__wrapped__``
        (use `functools.wraps`); otherwise the lock cannot tell it is the
        action's body and holds for the call only, as for a locked helper,
        not until the action and its children are done. A holder that is
        already being cancelled keeps its first cancel reason when it is
        preempted (``ActionInterrupted.reason``); the ``resource.preempted``
        event still records the preemption.

    Raises:
        InvalidResourceError: ``resource`` is not a resource (a bare ``@lock``
            without ``(RESOURCE)`` included).
        LockUsageError: Bad options; used outside an action; a plain ``with``.

    Examples:
        >>> from pyrobots_aio import Robot, action
        >>> from pyrobots_aio.actions import lock
        >>> from pyrobots_aio.resources import CompoundResource, Resource
        >>> ARMS = CompoundResource(Resource("l_arm"), Resource("r_arm"), name="arms")
        >>> @action
        ... @lock(ARMS)
        ... async def lift_box(robot: Robot) -> None:
        ...     await robot.sleep(1)
        >>> @action
        ... async def wave(robot: Robot) -> None:
        ...     async with lock(Resource("l_arm"), wait=False):
        ...         await robot.sleep(1)
    """
    _refuse_bare(resource)
    return Lock(resource, wait, priority, preempt)


def _refuse_bare(resource: object) -> None:
    """Raise if ``lock`` got a function: a bare ``@lock`` with nothing to take."""
    if callable(resource):  # resources are not callable
        name = getattr(resource, "__name__", repr(resource))
        msg = (
            f"lock() got the function {name!r} instead of a resource: a bare @lock names "
            "nothing to take; write @lock(RESOURCE), e.g. @lock(Resource('wheels'))"
        )
        raise InvalidResourceError(msg)


def _manager_of(robot: object, what: str) -> ResourceManager[ActionHandle[Any]]:
    manager = getattr(robot, "resources", None)
    if not isinstance(manager, ResourceManager):
        msg = f"{what} needs a robot with .resources (a ResourceManager), got {robot!r}"
        raise LockUsageError(msg)
    return manager


def _wrap(locked: _Locked) -> Callable[..., Coroutine[Any, Any, Any]]:
    """The ``async def`` that takes ``locked.resources`` and then runs ``locked.fn``."""
    fn, resources = locked.fn, locked.resources
    wait, priority, preempt = locked.options
    name = getattr(fn, "__name__", repr(fn))

    @functools.wraps(fn)
    async def take_then_run(*args: Any, **kwargs: Any) -> Any:
        handle = current_action.get()
        if handle is None:
            msg = (
                f"@lock on {name!r} needs to run inside an action; put @action on it and "
                f"start it as {name}(robot, ...)"
            )
            raise LockUsageError(msg)
        what = f"@lock on {name!r} (its first argument)"
        manager = _manager_of(args[0] if args else None, what)
        grant = await manager.acquire(
            handle, *resources, wait=wait, priority=priority, preempt=preempt
        )
        if _is_body(handle._fn, take_then_run):  # hold until the action is done
            grant.until_done = True
            handle.add_finalizer(grant.release)
            return await fn(*args, **kwargs)
        try:  # a locked helper awaited inside some action: hold for the call
            return await fn(*args, **kwargs)
        finally:
            grant.release()

    setattr(take_then_run, _MARK, locked)
    return take_then_run


def _is_body(fn: Callable[..., object] | None, wrapper: Callable[..., object]) -> bool:
    """Whether ``wrapper`` is the action function ``fn``, or wrapped by it (``__wrapped__``)."""
    return fn is not None and inspect.unwrap(fn, stop=lambda f: f is wrapper) is wrapper
