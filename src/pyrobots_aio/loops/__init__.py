"""The event loops of simulated time: lockstep virtual time and scaled time."""

from ._scaled import ScaledTimeLoop as ScaledTimeLoop
from ._scaled import scaled_loop as scaled_loop
from ._virtual import VirtualTimeLoop as VirtualTimeLoop
from ._virtual import VirtualTimePolicy as VirtualTimePolicy
from ._virtual import is_virtual as is_virtual
from ._virtual import new_virtual_loop as new_virtual_loop

__all__ = [
    "ScaledTimeLoop",
    "VirtualTimeLoop",
    "VirtualTimePolicy",
    "is_virtual",
    "new_virtual_loop",
    "scaled_loop",
]
