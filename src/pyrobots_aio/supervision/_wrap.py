"""What `retry` and `timeout` share: decorators from an action to an action.

Each takes an `Action` (``@retry(3)`` above ``@action``), a `BoundAction`
(``retry(3)(robot.lift)()``, the call form) or a plain ``async def`` taking
the robot first (made an action), and gives back the same kind, with the same
parameters and result type (ParamSpec), so type checkers see the real call.
"""

from __future__ import annotations

import abc
import inspect
from typing import TYPE_CHECKING, Any, Concatenate, ParamSpec, TypeVar, overload

from ..actions import Action, BoundAction, action

if TYPE_CHECKING:
    from collections.abc import Callable, Coroutine

P = ParamSpec("P")
T = TypeVar("T")
R = TypeVar("R")


class ActionDecorator(abc.ABC):
    """A decorator from an action to an action (`retry`, `timeout`): subclasses give `apply`."""

    @overload
    def __call__(self, target: Action[R, P, T]) -> Action[R, P, T]: ...

    @overload
    def __call__(self, target: BoundAction[P, T]) -> BoundAction[P, T]: ...

    @overload
    def __call__(
        self, target: Callable[Concatenate[R, P], Coroutine[Any, Any, T]]
    ) -> Action[R, P, T]: ...

    def __call__(self, target: Any) -> Any:
        if isinstance(target, BoundAction):
            return BoundAction(self.apply(target.action), target.robot)
        if isinstance(target, Action):
            return self.apply(target)
        if inspect.iscoroutinefunction(target):
            return self.apply(action(target))
        msg = (
            f"{self!r} decorates an @action, a bound action (robot.walk) or an 'async def' "
            f"taking the robot first, got {target!r}"
        )
        raise TypeError(msg)

    @abc.abstractmethod
    def apply(self, act: Action[Any, Any, Any]) -> Action[Any, Any, Any]:
        """The supervised action made from ``act`` (same name, parameters and result)."""
