"""Resources: what actions compete for, and the lock state that arbitrates them.

`Resource` and `CompoundResource` are plain immutable descriptions; the lock
state lives in each robot's `ResourceManager` (``robot.resources``), so two
robots in one process never share locks. The ``lock`` decorator and context
manager that actions use lives in `pyrobots_aio.actions`, one layer up.
"""

from ._grant import Grant as Grant
from ._grant import Owner as Owner
from ._manager import ResourceManager as ResourceManager
from ._resource import AnyResource as AnyResource
from ._resource import CompoundResource as CompoundResource
from ._resource import Resource as Resource

__all__ = [
    "AnyResource",
    "CompoundResource",
    "Grant",
    "Owner",
    "Resource",
    "ResourceManager",
]
