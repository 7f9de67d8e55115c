"""``@action``, the decorator: turns ``async def f(robot, ...)`` into an `Action`.

Apart from `Action` itself (``_decorator``): that module is compiled in a
built install, and a compiled function keeps no docstring, while this one is
the reference for how to write an action.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Concatenate, ParamSpec, TypeVar, overload

from ._decorator import Action

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

    from ._decorator import Body

P = ParamSpec("P")
T = TypeVar("T")
R = TypeVar("R")


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

    Example:
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
