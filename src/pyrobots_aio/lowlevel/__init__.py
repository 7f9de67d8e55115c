"""The parts the library's upper layers are built with, public for bases and worlds built alike.

``sim``, ``testing``, ``recording``, ``ros2`` and ``cli`` use the public API
only (pinned by tests/test_layers.py); these are the helpers they share that
a program does not need, and that a base, a simulated world or a recorder
written outside the library may use to behave as the library's own (trio
keeps such parts in ``trio.lowlevel``):

- checking numbers: `finite` reads a number a caller passes, or raises the
  `ValueError` every parameter of the library raises (naming the parameter,
  showing the value, saying what was expected); `as_float` reads one quietly;
  `shown` is how such messages show a value;
- differential-drive arithmetic: `limit_speeds` keeps both wheels within their
  top speed (as the simulator's and `pyrobots_aio.testing.FakeBase`'s worlds
  do), `wrap_angle` keeps a heading within ``[-pi, pi]``;
- `park`, the motion actions' pause hook (``@action(on_pause=park)``): a
  paused motion action stops the wheels;
- strict JSON, as recordings and the Foxglove channels write it:
  `strict_json` writes NaN and the infinities as null (`null_nonfinite`), and
  what ``json`` cannot encode as `jsonable` makes it.

Layer: beside ``motion`` and ``supervision`` (it re-exports ``_core`` and
``motion`` parts), below ``recording``, ``sim``, ``testing``, ``ros2`` and
``cli``.
"""

from .._core._json import jsonable as jsonable
from .._core._json import null_nonfinite as null_nonfinite
from .._core._json import strict_json as strict_json
from .._core._numbers import as_float as as_float
from .._core._numbers import finite as finite
from .._core._numbers import shown as shown
from ..motion._base import park as park
from ..motion._math import limit_speeds as limit_speeds
from ..motion._math import wrap_angle as wrap_angle

__all__ = [
    "as_float",
    "finite",
    "jsonable",
    "limit_speeds",
    "null_nonfinite",
    "park",
    "shown",
    "strict_json",
    "wrap_angle",
]
