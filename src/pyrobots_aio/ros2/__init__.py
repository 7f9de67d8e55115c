"""The robot over ROS 2: a node per robot, topics into ``robot.state``, services, goals.

Needs the ``ros2`` extra (``pip install "pyrobots-aio[ros2]"``: the ROS 2
Python wheels, Fast DDS included) or a sourced ROS 2 install; this module
imports without them, and creating a node says what to install.

``attach_ros2(robot)`` gives any robot a `Ros2Node` as ``robot.ros2``,
running inside ``async with robot``:

- ``robot.ros2.subscribe(topic, msg_type, to_state=...)`` writes every
  message into ``robot.state`` (a key, a field map, or a function);
- ``robot.ros2.publisher(topic, msg_type)`` publishes;
- ``await robot.ros2.call(service, request)`` calls a service (cancellable);
- ``robot.ros2.goal(action, goal)`` runs a ROS 2 action goal as a
  pyrobots_aio action: cancelling it cancels the goal, feedback goes to the
  state, the goal's result is the action's result;
- ``robot.ros2.serve_action(name, action_type, fn)`` and
  ``serve_service(name, srv_type, fn)`` serve the executive to ROS 2: each
  goal or request runs ``fn`` as a pyrobots_aio action (resources,
  priorities, pause and the emergency stop apply; a ROS 2 cancel arrives as
  ``ActionCancelled``);
- ``/diagnostics`` reports whether the watched state is fresh.

`Ros2Robot` is a `pyrobots_aio.motion.DriveBase` whose backend
(`Ros2Backend`) speaks a `Profile`: one table of topic names, types and
conversions, used by ``pyrobots-aio sim-node`` as well. `STANDARD` is the
standard messages' (``cmd_vel``, ``odom``, IR ``Range``, bumper/cliff/dock
``Bool``); the motion actions and the random walk run on it as on the simulator.
Its `TfBuffer` keeps what ``tf`` and ``tf_static`` broadcast, so ``robot.poses``
places a base's sensor frames; `TfBroadcaster` is sim-node's end of tf.
`CREATE3` is the iRobot Create 3's (``hazard_detection``, ``ir_intensity``,
``dock_status``; its action servers in `CREATE3_ACTIONS`, which
`serve_create3` serves over any `pyrobots_aio.motion.DriveBase`).

`build_interfaces` builds the interface packages PyPI lacks (``tf2_msgs``,
``irobot_create_msgs``) from the definitions pyrobots_aio carries, into this
environment (``pyrobots-aio ros2 interfaces build``; the ``ros2-build`` extra).

Layer: above ``sim`` (which it does not import) and below ``cli``, on the public API only.
A program beside a ``sim-node --rate R`` runs at its pace with
`pyrobots_aio.loops.run_scaled`.
"""

from ._backend import DOCK_IN_ODOM as DOCK_IN_ODOM
from ._backend import Ros2Backend as Ros2Backend
from ._create3 import CREATE3 as CREATE3
from ._create3 import CREATE3_ACTIONS as CREATE3_ACTIONS
from ._create3 import IR_MAX_INTENSITY as IR_MAX_INTENSITY
from ._create3_serve import serve_create3 as serve_create3
from ._interfaces import InterfaceBuild as InterfaceBuild
from ._interfaces import InterfaceOutcome as InterfaceOutcome
from ._interfaces import build_interfaces as build_interfaces
from ._interfaces import interface_packages as interface_packages
from ._node import Ros2Node as Ros2Node
from ._node import attach_ros2 as attach_ros2
from ._profiles import PROFILES as PROFILES
from ._profiles import STANDARD as STANDARD
from ._profiles import Odometry as Odometry
from ._profiles import Profile as Profile
from ._profiles import Topic as Topic
from ._profiles import profile_named as profile_named
from ._robot import Ros2Robot as Ros2Robot
from ._serve import Ros2ActionServer as Ros2ActionServer
from ._serve import Ros2ServiceServer as Ros2ServiceServer
from ._tf import TfBroadcaster as TfBroadcaster
from ._tf import TfBuffer as TfBuffer
from ._tf import tf_available as tf_available
from ._topics import Ros2Publisher as Ros2Publisher
from ._topics import Ros2Subscription as Ros2Subscription
from ._topics import ToState as ToState

__all__ = [
    "CREATE3",
    "CREATE3_ACTIONS",
    "DOCK_IN_ODOM",
    "IR_MAX_INTENSITY",
    "PROFILES",
    "STANDARD",
    "InterfaceBuild",
    "InterfaceOutcome",
    "Odometry",
    "Profile",
    "Ros2ActionServer",
    "Ros2Backend",
    "Ros2Node",
    "Ros2Publisher",
    "Ros2Robot",
    "Ros2ServiceServer",
    "Ros2Subscription",
    "TfBroadcaster",
    "TfBuffer",
    "ToState",
    "Topic",
    "attach_ros2",
    "build_interfaces",
    "interface_packages",
    "profile_named",
    "serve_create3",
    "tf_available",
]
