"""Recording in memory: the sink that keeps what it is given, and its recorder."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._recorder import Recorder, RecordingOptions
from ._recording import Recording, RecordingHeader, SeriesBuilder

if TYPE_CHECKING:
    from collections.abc import Collection, Mapping

    from pyrobots_aio import ExecEvent
    from pyrobots_aio.poses import Pose2D


class MemorySink:
    """A `Sink` that keeps the run in memory; `recording` returns it for replay.

    Attributes:
        events: The executive events, in order.
        header: The header facts (None until opened).
        end: The loop time the recorder was closed at (None while open).
    """

    def __init__(self) -> None:
        self.events: list[ExecEvent] = []
        self.header: RecordingHeader | None = None
        self.end: float | None = None
        self._closed = False
        self._series = SeriesBuilder()

    def open(self, header: RecordingHeader) -> None:
        """Keep the header."""
        self.header = header

    def write_event(self, event: ExecEvent) -> None:
        """Keep one event."""
        self.events.append(event)

    def write_samples(self, time: float, values: Mapping[str, object], pose: Pose2D | None) -> None:
        """Keep the state values written at ``time`` and the pose."""
        add = self._series.add
        for key, value in values.items():
            add(time, key, value)
        if pose is not None:
            self._series.add_pose(time, *pose)

    def flush(self) -> None:
        """Nothing to do: everything is kept as it comes."""

    def close(self, end: float | None) -> None:
        """Keep the end time."""
        self.end, self._closed = end, True

    def recording(self) -> Recording:
        """What it holds as a `Recording` (complete once closed)."""
        header = self.header if self.header is not None else RecordingHeader(state_keys=None)
        samples, poses = self._series.build(header.pose_frame)
        end = self.end if self._closed else None
        return Recording(header, tuple(self.events), end=end, samples=samples, poses=poses)

    def __repr__(self) -> str:
        return f"<MemorySink {len(self.events)} events>"


class MemoryRecorder(Recorder[MemorySink]):
    """A recorder that keeps the run in memory (a `MemorySink`), for tests and the CLI.

    Args:
        state_keys: State keys to sample (None: every key; see `RecordingOptions`).
        sample_rate: None (default): every change; a number downsamples numbers
            and the pose to at most that many samples per second.
        pose_frame: The frame whose pose in ``map`` is recorded (None: none).
        metadata: Free JSON-friendly facts for the header.

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import Robot, action
        >>> from pyrobots_aio.recording import MemoryRecorder, summarize
        >>> @action
        ... async def hello(robot: Robot) -> None:
        ...     await robot.sleep(0.01)
        >>> async def main() -> int:
        ...     robot = Robot()
        ...     with MemoryRecorder().attach(robot) as recorder:
        ...         async with robot:
        ...             await hello(robot)
        ...     return summarize(recorder.recording()).actions
        >>> asyncio.run(main())
        1
    """

    def __init__(
        self,
        *,
        state_keys: Collection[str] | None = None,
        sample_rate: float | None = None,
        pose_frame: str | None = "base_link",
        metadata: Mapping[str, object] | None = None,
    ) -> None:
        options = RecordingOptions(state_keys, sample_rate, pose_frame, metadata or {})
        super().__init__(MemorySink(), options)

    @property
    def events(self) -> list[ExecEvent]:
        """The executive events so far."""
        return self.sink.events

    def recording(self) -> Recording:
        """The run so far as a `Recording` (complete once the recorder is closed)."""
        return self.sink.recording()

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"<MemoryRecorder {state}, {len(self.events)} events>"
