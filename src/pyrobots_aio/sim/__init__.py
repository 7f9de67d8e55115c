"""The simulated robot: MuJoCo physics, SimRobot, and lockstep virtual time.

Needs the ``sim`` extra (``pip install -e ".[sim]"`` in a checkout). ``run(main)``
runs ``main`` on a virtual-time loop whose clock *is* simulation time: it is
`pyrobots_aio.loops.run_lockstep`, which holds the loops themselves.
"""

from ..loops import run_lockstep as run
from ..motion import WHEELS as WHEELS
from ._backend import SimBackend as SimBackend
from ._frames import WorldFrames as WorldFrames
from ._models import model_path as model_path
from ._models import models_dir as models_dir
from ._robot import SimRobot as SimRobot
from ._world import SimWorld as SimWorld

__all__ = [
    "WHEELS",
    "SimBackend",
    "SimRobot",
    "SimWorld",
    "WorldFrames",
    "model_path",
    "models_dir",
    "run",
]
