"""The event loops of simulated time, and a ``run`` for each (no simulator, no ROS 2 needed).

- **Lockstep virtual time**: `VirtualTimeLoop` jumps to its next timer whenever
  it would wait, so a minute of ``asyncio.sleep`` takes no time and the same
  program always sees the same clock. `run_lockstep(main, *args)` runs a
  program on one (``pyrobots_aio.sim.run`` is the same function); the pytest
  plugin's ``virtual_time`` marker runs a test on one.
- **Scaled time**: `ScaledTimeLoop` runs ``rate`` times faster than the wall
  clock. `run_scaled(main, *args, rate=R)` runs a program at the pace of a
  ``pyrobots-aio sim-node --rate R``.
- Each closes safely under signals (rate 1 too): a second Ctrl-C while the
  loop closes is never written to a closed pipe.

Layer: right above ``_core``; ``sim``, ``ros2``, ``cli`` and ``testing`` all
use it, and it imports none of them.
"""

from ._scaled import ScaledTimeLoop as ScaledTimeLoop
from ._scaled import run_scaled as run_scaled
from ._scaled import scaled_loop as scaled_loop
from ._virtual import VirtualTimeLoop as VirtualTimeLoop
from ._virtual import is_virtual as is_virtual
from ._virtual import new_virtual_loop as new_virtual_loop
from ._virtual import run_lockstep as run_lockstep

__all__ = [
    "ScaledTimeLoop",
    "VirtualTimeLoop",
    "is_virtual",
    "new_virtual_loop",
    "run_lockstep",
    "run_scaled",
    "scaled_loop",
]
