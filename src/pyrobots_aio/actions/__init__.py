"""Actions: ``@action``, handles, outcomes and the executive that runs them."""

from ._decorator import Action as Action
from ._decorator import BoundAction as BoundAction
from ._decorator import action as action
from ._handle import ActionHandle as ActionHandle
from ._handle import current_action as current_action
from ._info import ActionInfo as ActionInfo
from ._lock import lock as lock
from ._states import ActionState as ActionState
from ._states import Outcome as Outcome

__all__ = [
    "Action",
    "ActionHandle",
    "ActionInfo",
    "ActionState",
    "BoundAction",
    "Outcome",
    "action",
    "current_action",
    "lock",
]
