"""Telemetry: the Foxglove channels of a run, state sampling, and the live view.

- `FoxgloveChannels` turns the executive's events, state samples, the pose,
  log records and a simulated world's arena (`floor_plan`, read as
  `FloorShape` values, as the replay page's map reads it) into the messages of
  the Foxglove channels (`FIXED_CHANNELS`, `ARENA`, schemas in `SCHEMAS`,
  strict JSON: `pyrobots_aio.lowlevel.strict_json`);
- `StateSampler` passes on what each write of a robot's state brings;
- `LiveView` serves those channels over Foxglove's WebSocket protocol while a
  robot runs (``Robot(serve=PORT)``).

The recorders (`pyrobots_aio.recording`) and the live view share them, so a
recording and the live view carry the same messages.

Layer: below the robot, beside ``actions`` and ``events``. The robot owns its
live view, so it imports telemetry; telemetry reads the robot only through
`TelemetrySource` (its state, poses, clock and instruments), a protocol that
`pyrobots_aio.Robot` meets, and never imports the robot.
"""

from ._arena import ARENA as ARENA
from ._arena import SCENE_UPDATE as SCENE_UPDATE
from ._arena import FloorShape as FloorShape
from ._arena import floor_plan as floor_plan
from ._channels import EVENT as EVENT
from ._channels import FIXED_CHANNELS as FIXED_CHANNELS
from ._channels import POSE_IN_FRAME as POSE_IN_FRAME
from ._channels import SAMPLE as SAMPLE
from ._channels import SCHEMAS as SCHEMAS
from ._channels import FoxgloveChannels as FoxgloveChannels
from ._channels import LogForwarder as LogForwarder
from ._channels import Message as Message
from ._live import LiveView as LiveView
from ._sampling import StateSampler as StateSampler
from ._source import TelemetrySource as TelemetrySource

__all__ = [
    "ARENA",
    "EVENT",
    "FIXED_CHANNELS",
    "POSE_IN_FRAME",
    "SAMPLE",
    "SCENE_UPDATE",
    "SCHEMAS",
    "FloorShape",
    "FoxgloveChannels",
    "LiveView",
    "LogForwarder",
    "Message",
    "StateSampler",
    "TelemetrySource",
    "floor_plan",
]
