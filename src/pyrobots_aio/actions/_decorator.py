"""``@action``: turn ``async def f(robot, ...)`` into something that starts at once.

Calling an action schedules it and returns an `ActionHandle` without blocking.
``Action`` is also a descriptor, so ``@action`` methods on a ``Robot`` subclass
bind like methods: ``robot.safe_walk(0.3)``.
"""

from __future__ import annotations

import functools
import inspect
from typing import (
    TYPE_CHECKING,
    Any,
    Concatenate,
    Generic,
    ParamSpec,
    Protocol,
    TypeVar,
    overload,
    runtime_checkable,
)

from .._exceptions import ActionDefinitionError

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

    from ._executive import Executive
    from ._handle import ActionHandle
    from ._pause import Hooks

P = ParamSpec("P")
T = TypeVar("T")
R = TypeVar("R")
if TYPE_CHECKING:
    Body = Callable[Concatenate[R, P], Coroutine[Any, Any, T]]
    """An action's function: an ``async def`` taking the robot first."""


@runtime_checkable
class Runner(Protocol):
    """What an action is called with first: something whose executive runs it (a `Robot`)."""

    @property
    def executive(self) -> Executive:
        """The executive that starts the robot's actions."""


def executive_of(robot: object, name: str) -> Executive:
    """The executive of ``robot`` (a `Runner`), or a clear error naming what was passed instead."""
    if not isinstance(robot, Runner):
        msg = (
            f"action {name!r} needs the robot as its first argument, got {robot!r}; "
            f"call it as {name}(robot, ...) or robot.{name}(...)"
        )
        raise ActionDefinitionError(msg)
    return robot.executive


class Action(Generic[R, P, T]):
    """An action: an ``async def`` whose first parameter is the robot.

    Created by `action`; calling it starts the action and returns its handle.
    """

    # Slots for what every call reads: the wrapper's attributes (update_wrapper) would
    # otherwise turn the instance dict into one Python 3.11 cannot specialize lookups in.
    __slots__ = ("__dict__", "__weakref__", "fn", "hooks", "name")

    def __init__(
        self,
        fn: Callable[Concatenate[R, P], Coroutine[Any, Any, T]],
        hooks: Hooks | None = None,
    ) -> None:
        if not inspect.iscoroutinefunction(fn):
            msg = (
                f"@action needs an 'async def' function taking the robot first, "
                f"got {fn!r}; write 'async def {getattr(fn, '__name__', 'name')}(robot, ...)'"
            )
            raise ActionDefinitionError(msg)
        self.fn = fn
        self.hooks = hooks
        self.name: str = getattr(fn, "__name__", repr(fn))
        functools.update_wrapper(self, fn)

    def __call__(self, robot: R, /, *args: P.args, **kwargs: P.kwargs) -> ActionHandle[T]:
        runner: Any = robot  # a `Runner`, or the error below
        try:
            executive: Executive = runner.executive
        except AttributeError:
            executive = executive_of(robot, self.name)  # raises, naming what was passed
        fn: Callable[..., Coroutine[Any, Any, T]] = self.fn
        # A call through ``*``/``**`` costs about 100 ns more than a plain one (a bare
        # task starts in 6 us): only a call that passes arguments pays for it.
        if kwargs:
            coro = fn(robot, *args, **kwargs)
        elif args:
            coro = fn(robot, *args)
        else:
            coro = fn(robot)
        return executive.spawn(self.name, fn, coro, self.hooks)

    @overload
    def __get__(self, instance: None, owner: type[Any]) -> Action[R, P, T]: ...

    @overload
    def __get__(self, instance: R, owner: type[Any]) -> BoundAction[P, T]: ...

    def __get__(self, instance: R | None, owner: type[Any]) -> Action[R, P, T] | BoundAction[P, T]:
        if instance is None:
            return self
        return BoundAction(self, instance)

    def __repr__(self) -> str:
        return f"<action {self.name}>"


class BoundAction(Generic[P, T]):
    """An action bound to a robot: ``robot.walk(0.2)`` starts it on that robot."""

    __slots__ = ("action", "robot")

    def __init__(self, action: Action[Any, P, T], robot: object) -> None:
        self.action = action
        self.robot = robot

    def __call__(self, *args: P.args, **kwargs: P.kwargs) -> ActionHandle[T]:
        return self.action(self.robot, *args, **kwargs)

    @property
    def __name__(self) -> str:
        return self.action.name

    def __repr__(self) -> str:
        return f"<action {self.action.name} bound to {self.robot!r}>"


@overload
def action(fn: Callable[Concatenate[R, P], Coroutine[Any, Any, T]]) -> Action[R, P, T]: ...


@overload
def action(
    *,
    on_pause: Callable[[R], object] | None = None,
    on_resume: Callable[[R], object] | None = None,
) -> Callable[[Callable[Concatenate[R, P], Coroutine[Any, Any, T]]], Action[R, P, T]]: ...


def action(
    fn: Callable[Concatenate[R, P], Coroutine[Any, Any, T]] | None = None,
    *,
    on_pause: Callable[[R], object] | None = None,
    on_resume: Callable[[R], object] | None = None,
) -> (
    Action[R, P, T]
    | Callable[[Callable[Concatenate[R, P], Coroutine[Any, Any, T]]], Action[R, P, T]]
):
    """Turn an ``async def`` taking the robot first into an action.

    ``@action(on_pause=..., on_resume=...)`` also gives hooks, called with the
    robot when the action freezes and thaws (`ActionHandle.pause`): stop the
    actuators there, and restore them. A hook may be a plain function or
    return an awaitable (run on its own; a failure is logged).

    Examples:
        >>> from pyrobots_aio import Robot, action, ActionCancelled
        >>> @action
        ... async def safe_walk(robot: Robot, speed: float = 0.2) -> None:
        ...     try:
        ...         await robot.sleep(10)
        ...     except ActionCancelled:
        ...         await robot.sleep(0.1)  # cleanup may await
        ...         raise
        >>> safe_walk
        <action safe_walk>
        >>> @action(on_pause=lambda robot: robot.state.update(motors="off"))
        ... async def wave(robot: Robot) -> None:
        ...     await robot.sleep(1)
        >>> wave
        <action wave>
    """
    hooks = None if on_pause is None and on_resume is None else (on_pause, on_resume)
    if fn is not None:
        return Action(fn, hooks)

    def decorate(f: Body[R, P, T]) -> Action[R, P, T]:
        return Action(f, hooks)

    return decorate
