"""Recording and replay: recorders on the instrumentation hook, summaries, timelines.

Layer: on top; uses only the public API of ``pyrobots_aio``.

Record a run, then read it back::

    robot = SimRobot(seed=1)
    with JsonlRecorder("run.jsonl").attach(robot):  # or McapRecorder("run.mcap")
        async with robot:
            ...
    recording = load("run.jsonl")
    print(format_summary(summarize(recording)))
    Path("run.html").write_text(render_timeline_html(recording))

A recording holds the executive's events, every state key at each change (a
simulated robot's sensors at its control rate) and the robot's pose in
``map``; `load` reads JSON Lines and MCAP alike. Recorders: `JsonlRecorder`
(built in), `McapRecorder` (the ``mcap`` extra; opens in Foxglove, on its
well-known schemas), `MemoryRecorder` (in memory, for tests and the CLI).

Each is a `Recorder` on a sink (`JsonlSink`, `McapSink`, `MemorySink`) with
`RecordingOptions`; any object with the `Sink` methods is a sink too, and
receives the typed events (``pyrobots_aio.ActionFinished`` ...)::

    with Recorder(MySink(), RecordingOptions(state_keys=["bumper"])).attach(robot):
        ...
"""

from ._format import format_summary as format_summary
from ._format import shown as shown
from ._jsonl import JsonlRecorder as JsonlRecorder
from ._jsonl import JsonlSink as JsonlSink
from ._mcap import McapRecorder as McapRecorder
from ._mcap import McapSink as McapSink
from ._memory import MemoryRecorder as MemoryRecorder
from ._memory import MemorySink as MemorySink
from ._recorder import Recorder as Recorder
from ._recorder import RecordingOptions as RecordingOptions
from ._recorder import Sink as Sink
from ._recording import FORMAT as FORMAT
from ._recording import VERSION as VERSION
from ._recording import PoseTrack as PoseTrack
from ._recording import Recording as Recording
from ._recording import RecordingHeader as RecordingHeader
from ._recording import Series as Series
from ._recording import load as load
from ._summary import ActionStats as ActionStats
from ._summary import Cancellation as Cancellation
from ._summary import Failure as Failure
from ._summary import Outcomes as Outcomes
from ._summary import ResourceStats as ResourceStats
from ._summary import Summary as Summary
from ._summary import summarize as summarize
from ._timeline import render_timeline_html as render_timeline_html

__all__ = [
    "FORMAT",
    "VERSION",
    "ActionStats",
    "Cancellation",
    "Failure",
    "JsonlRecorder",
    "JsonlSink",
    "McapRecorder",
    "McapSink",
    "MemoryRecorder",
    "MemorySink",
    "Outcomes",
    "PoseTrack",
    "Recorder",
    "Recording",
    "RecordingHeader",
    "RecordingOptions",
    "ResourceStats",
    "Series",
    "Sink",
    "Summary",
    "format_summary",
    "load",
    "render_timeline_html",
    "shown",
    "summarize",
]
