"""The recorder: attached to a robot, it feeds a `Sink` the run's events, state and pose.

A recorder is an `Instrument`: the executive calls its ``on_event`` inline, so
the path to the sink is short (a sink appends to a buffer and writes in bulk).
The recorder adds what the instrumentation hook alone does not give: the
header facts (robot class, seed, the arena's floor plan), the robot's state and
pose sampled at each write of the state (each control tick of a simulated
robot), as `RecordingOptions` say, and a lifecycle (``attach`` ... ``close``,
or a ``with`` block). Where the run goes is the sink's business: `JsonlSink`,
`McapSink`, `MemorySink`, or any object with the `Sink` methods.
"""

from __future__ import annotations

import asyncio
import dataclasses
import datetime
import logging
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Generic, Protocol, Self, TypeVar

from pyrobots_aio import RecordingError
from pyrobots_aio.telemetry import StateSampler, floor_plan

from ._recording import RecordingHeader

if TYPE_CHECKING:
    from collections.abc import Collection, Mapping

    from pyrobots_aio import ExecEvent, Robot
    from pyrobots_aio.poses import Pose2D

_log = logging.getLogger("pyrobots_aio.recording")


def _loop_time() -> float | None:
    try:
        return asyncio.get_running_loop().time()
    except RuntimeError:
        return None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@dataclass(frozen=True, slots=True)
class RecordingOptions:
    """What a `Recorder` samples besides the events, and the free facts of its header.

    Args:
        state_keys: State keys to sample: the value after each write that
            changes it. None (default): every key. Kept as a tuple; one string
            is one key.
        sample_rate: None (default): every change is recorded, so a simulated
            robot's sensors and pose are recorded at its control rate. A number
            downsamples numbers and the pose to at most that many samples per
            second and key; booleans, strings and other discrete values are
            always recorded on every change, so a one-tick bumper press is never lost.
        pose_frame: The frame whose pose in ``map`` is recorded with each state
            write, if the robot knows it (None: no pose).
        metadata: Free JSON-friendly facts to store in the header.

    Raises:
        ValueError: ``sample_rate`` is not a positive number or None.
    """

    state_keys: Collection[str] | None = None
    sample_rate: float | None = None
    pose_frame: str | None = "base_link"
    metadata: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        rate = self.sample_rate
        if rate is not None and not (_is_number(rate) and math.isfinite(rate) and rate > 0):
            msg = (
                f"sample_rate must be a positive number of samples per second or None, got {rate!r}"
            )
            raise ValueError(msg)
        keys = self.state_keys
        if keys is not None:  # kept as a tuple; a string is one key
            frozen = (keys,) if isinstance(keys, str) else tuple(keys)
            object.__setattr__(self, "state_keys", frozen)

    @property
    def period(self) -> float:
        """Least seconds between two samples of a number or the pose (0: every change)."""
        # A hair under the period, so that a write due exactly on time is not lost to rounding.
        return 0.0 if self.sample_rate is None else (1.0 - 1e-6) / self.sample_rate


class Sink(Protocol):
    """Where a `Recorder` writes a run: a file format, memory, a network.

    The recorder calls `open` once, before anything else (at `Recorder.attach`,
    or at the first event); then `write_event` and `write_samples` as the run
    goes, from the event loop's thread; `flush` when asked; `close` once, last.
    ``write_event`` runs inside the executive: keep it short and never block
    (buffer, and write in bulk).

    Example, a sink that keeps the events in a list::

        class ListSink:
            def __init__(self) -> None:
                self.events: list[ExecEvent] = []
            def open(self, header: RecordingHeader) -> None: ...
            def write_event(self, event: ExecEvent) -> None:
                self.events.append(event)
            def write_samples(self, time, values, pose) -> None: ...
            def flush(self) -> None: ...
            def close(self, end: float | None) -> None: ...

        with Recorder(ListSink()).attach(robot):
            ...
    """

    def open(self, header: RecordingHeader) -> None:
        """Start the output with the header facts."""

    def write_event(self, event: ExecEvent) -> None:
        """Take one executive event."""

    def write_samples(self, time: float, values: Mapping[str, object], pose: Pose2D | None) -> None:
        """Take the state ``values`` written at ``time`` (changed or due), and the pose."""

    def flush(self) -> None:
        """Write what is buffered now."""

    def close(self, end: float | None) -> None:
        """Write what is buffered and the end (the loop time at close, if known); close."""


SinkT_co = TypeVar("SinkT_co", bound=Sink, covariant=True)


class Recorder(Generic[SinkT_co]):
    """Records a robot's run into ``sink``: its events, and its state and pose as ``options`` say.

    Users call `attach`, `close`, or use ``with``. `JsonlRecorder`,
    `McapRecorder` and `MemoryRecorder` are recorders on the built-in sinks.

    Args:
        sink: Where the run goes (see `Sink`).
        options: What to sample and the header's free facts (default: every
            state key at every change, the pose of ``base_link``).

    Examples:
        >>> import asyncio
        >>> from pyrobots_aio import ActionFinished, Robot, action
        >>> from pyrobots_aio.recording import MemorySink, Recorder
        >>> @action
        ... async def hello(robot: Robot) -> None:
        ...     await robot.sleep(0.01)
        >>> async def main() -> list[str]:
        ...     robot, sink = Robot(), MemorySink()
        ...     with Recorder(sink).attach(robot):
        ...         async with robot:
        ...             await hello(robot)
        ...     return [e.outcome for e in sink.events if isinstance(e, ActionFinished)]
        >>> asyncio.run(main())
        ['succeeded']
    """

    def __init__(self, sink: SinkT_co, options: RecordingOptions | None = None) -> None:
        self._sink = sink
        self.options = options if options is not None else RecordingOptions()
        """What this recorder samples."""
        keys = self.options.state_keys
        self._header = RecordingHeader(
            state_keys=None if keys is None else tuple(keys),
            sample_rate=self.options.sample_rate,
            metadata=dict(self.options.metadata),
        )
        self._robot: Robot | None = None
        self._sampler = StateSampler(
            self._take_samples,
            keys=None if keys is None else frozenset(keys),
            period=self.options.period,
            pose_frame=self.options.pose_frame,
        )
        self._write_event = sink.write_event
        self._write_samples = sink.write_samples
        self._ready = False  # opened and not closed: the sink takes what comes
        self._opened = False
        self._closed = False
        self._late = False
        self._count = 0
        self._last_time: float | None = None

    @property
    def sink(self) -> SinkT_co:
        """Where the run goes."""
        return self._sink

    @property
    def header(self) -> RecordingHeader:
        """The header facts: complete once the recorder is open (attached, or a first event)."""
        return self._header

    # -- lifecycle ----------------------------------------------------------

    def attach(self, robot: Robot) -> Self:
        """Record ``robot``: add this recorder to its instruments and sample its state.

        Attach before ``async with robot`` to record the whole run, shutdown
        included, and close after it (``with recorder.attach(robot): async with
        robot: ...``).

        Returns:
            This recorder, so that ``with JsonlRecorder(path).attach(robot):`` reads well.

        Raises:
            RecordingError: The recorder is closed or already attached.
        """
        if self._closed or self._robot is not None:
            state = "closed" if self._closed else f"attached to {self._robot!r}"
            msg = f"{type(self).__name__} is {state}; create a new recorder for {robot!r}"
            raise RecordingError(msg)
        self._robot = robot
        seed = getattr(robot, "seed", None)
        frame = self.options.pose_frame
        self._header = dataclasses.replace(
            self._header,
            robot=type(robot).__name__,
            seed=seed if isinstance(seed, int) and not isinstance(seed, bool) else None,
            floor_plan=tuple(floor_plan(robot)),
            pose_frame=frame if frame is not None and frame in robot.poses.frames() else None,
        )
        if not any(instrument is self for instrument in robot.instruments):
            robot.instruments.add(self)
        self._sampler.pose_frame = self._header.pose_frame
        self._ensure_open()
        self._sampler.start(robot)
        return self

    def close(self) -> None:
        """Detach from the robot, have the sink write what is buffered and the end, close.

        Closing twice does nothing. Events that arrive after closing (the robot
        still runs and the recorder was passed in ``instruments=``) are dropped
        with one warning.

        Raises:
            RecordingError: The sink could not write the recording (`JsonlSink`:
                a full disk); the sink's message says what it kept.
        """
        if self._closed:
            return
        self._ensure_open()
        self._closed, self._ready = True, False
        self._sampler.stop()
        if self._robot is not None:
            self._robot.instruments.remove(self)
        now = _loop_time()
        self._sink.close(now if now is not None else self._last_time)

    @property
    def closed(self) -> bool:
        """Whether `close` was called."""
        return self._closed

    def __enter__(self) -> Self:
        self._ensure_open()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def flush(self) -> None:
        """Have the sink write what it buffers now."""
        if self._ready:
            self._sink.flush()

    # -- what comes in --------------------------------------------------------

    def on_event(self, event: ExecEvent) -> None:
        """Record one executive event (called by the robot's instruments)."""
        if not self._ready and not self._get_ready(event.time):
            return
        self._last_time = event.time
        self._count += 1
        self._write_event(event)

    def _take_samples(self, time: float, values: dict[str, object], pose: Pose2D | None) -> None:
        if not self._ready and not self._get_ready(time):
            return
        self._last_time = time
        self._count += 1
        self._write_samples(time, values, pose)

    def _get_ready(self, time: float) -> bool:
        """Open at the first record; after closing, drop it (with one warning)."""
        if self._closed:
            if not self._late:
                self._late = True
                _log.warning("%r is closed; events are no longer recorded", self)
            return False
        self._ensure_open(time)
        return True

    def _ensure_open(self, first_time: float | None = None) -> None:
        if self._opened:
            return
        self._opened = True
        now = _loop_time()
        # Wall-clock date of the run, for people and tools (Foxglove); never used for timing.
        created = datetime.datetime.now(datetime.UTC)
        self._header = dataclasses.replace(
            self._header,
            created=created.isoformat(timespec="milliseconds"),
            t0=now if now is not None else first_time,
        )
        self._sink.open(self._header)
        self._ready = not self._closed

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"<{type(self).__name__} {self._sink!r} {state}, {self._count} events>"
