"""The robot's state store: named values, timestamps, versions, change notification.

Layer: above ``_core``; uses only the standard library, ``_core`` and ``_exceptions``.
"""

from ._notify import Subscription as Subscription
from ._store import StateSample as StateSample
from ._store import StateStore as StateStore

__all__ = ["StateSample", "StateStore", "Subscription"]
