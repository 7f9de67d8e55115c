"""What every recorder shares: attaching to a robot, sampling its state and pose, closing.

A recorder is an `Instrument`: the executive calls its ``on_event`` inline, so
subclasses keep that path short (append to a buffer) and write in bulk. The
base class adds what the instrumentation hook alone does not give: the header
facts (robot class, seed, the arena's floor plan), the robot's state and pose
sampled at each write of the state (each control tick of a simulated robot),
and a lifecycle (``attach`` ... ``close``, or a ``with`` block).
"""

from __future__ import annotations

import asyncio
import datetime
import logging
import math
from typing import TYPE_CHECKING, Any, Self

from pyrobots_aio import ExecEvent, RecordingError
from pyrobots_aio.telemetry import Pose2D, StateSampler

from ._recording import FORMAT, VERSION, Recording, RecordingHeader, SeriesBuilder

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

    from pyrobots_aio import Robot

_log = logging.getLogger("pyrobots_aio.recording")


def _loop_time() -> float | None:
    try:
        return asyncio.get_running_loop().time()
    except RuntimeError:
        return None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def floor_plan(robot: Robot) -> list[dict[str, Any]]:
    """The static shapes of ``robot``'s world, if it has one (``SimRobot.world.floor_plan()``)."""
    world = getattr(robot, "world", None)
    plan = getattr(world, "floor_plan", None)
    return list(plan()) if callable(plan) else []


class Recorder:
    """The base of the recorders: attach to a robot, sample its state and pose, close.

    Subclasses implement ``_record(event)``, ``_record_samples(time, values, pose)``,
    ``_open(header)`` and ``_finish(end, count)``; users call `attach`, `close`
    or use ``with``.

    Args:
        state_keys: State keys to sample: the value after each write that
            changes it. None (default): every key.
        sample_rate: None (default): every change is recorded, so a simulated
            robot's sensors and pose are recorded at its control rate. A number
            downsamples numbers and the pose to at most that many samples per
            second and key; booleans, strings and other discrete values are
            always recorded on every change, so a one-tick bumper press is never lost.
        pose_frame: The frame whose pose in ``map`` is recorded with each state
            write, if the robot knows it (None: no pose).
        metadata: Free JSON-friendly facts to store in the header.
    """

    def __init__(
        self,
        *,
        state_keys: Iterable[str] | None = None,
        sample_rate: float | None = None,
        pose_frame: str | None = "base_link",
        metadata: Mapping[str, object] | None = None,
    ) -> None:
        if sample_rate is not None and not (
            _is_number(sample_rate) and math.isfinite(sample_rate) and sample_rate > 0
        ):
            msg = (
                "sample_rate must be a positive number of samples per second or None, "
                f"got {sample_rate!r}"
            )
            raise ValueError(msg)
        keys: tuple[str, ...] | None
        if state_keys is None:
            keys = None
        else:
            keys = (state_keys,) if isinstance(state_keys, str) else tuple(state_keys)
        self.state_keys = keys
        self.sample_rate = sample_rate
        self.pose_frame = pose_frame
        # A hair under the period, so that a write due exactly on time is not lost to rounding.
        self._period = 0.0 if sample_rate is None else (1.0 - 1e-6) / sample_rate
        self._header: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "created": None,
            "robot": None,
            "seed": None,
            "t0": None,
            "state_keys": None if keys is None else list(keys),
            "sample_rate": sample_rate,
            "pose_frame": None,
            "floor_plan": [],
            "metadata": dict(metadata or {}),
        }
        self._robot: Robot | None = None
        self._sampler = StateSampler(
            self._take_samples,
            keys=None if keys is None else frozenset(keys),
            period=self._period,
            pose_frame=pose_frame,
        )
        self._opened = False
        self._closed = False
        self._late = False
        self._count = 0
        self._last_time: float | None = None

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
        known = isinstance(seed, int) and not isinstance(seed, bool)
        self._header.update(robot=type(robot).__name__, seed=seed if known else None)
        self._header.update(floor_plan=floor_plan(robot))
        if not any(instrument is self for instrument in robot.instruments):
            robot.instruments.add(self)
        frame = self.pose_frame
        known = frame is not None and frame in robot.poses.frames()
        self._header["pose_frame"] = self._sampler.pose_frame = frame if known else None
        self._ensure_open()
        self._sampler.start(robot)
        return self

    def close(self) -> None:
        """Detach from the robot, write what is buffered and the end record, close.

        Closing twice does nothing. Events that arrive after closing (the robot
        still runs and the recorder was passed in ``instruments=``) are dropped
        with one warning.
        """
        if self._closed:
            return
        self._ensure_open()
        self.flush()
        self._closed = True
        self._sampler.stop()
        if self._robot is not None:
            self._robot.instruments.remove(self)
        now = _loop_time()
        self._finish(now if now is not None else self._last_time, self._count)

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
        """Write what is buffered now (recorders that buffer override this)."""

    # -- events ---------------------------------------------------------------

    def on_event(self, event: ExecEvent) -> None:
        """Record one executive event (called by the robot's instruments)."""
        if self._closed:
            self._dropped()
            return
        if not self._opened:
            self._ensure_open(event.time)
        self._count += 1
        self._last_time = event.time
        self._record(event)

    def _dropped(self) -> None:
        if not self._late:
            self._late = True
            _log.warning("%r is closed; events are no longer recorded", self)

    def _take_samples(self, time: float, values: dict[str, object], pose: Pose2D | None) -> None:
        if not self._opened:
            self._ensure_open(time)
        self._count += 1
        self._last_time = time
        self._record_samples(time, values, pose)

    def _ensure_open(self, first_time: float | None = None) -> None:
        if self._opened:
            return
        self._opened = True
        now = _loop_time()
        # Wall-clock date of the run, for people and tools (Foxglove); never used for timing.
        created = datetime.datetime.now(datetime.UTC)
        self._header.update(
            created=created.isoformat(timespec="milliseconds"),
            t0=now if now is not None else first_time,
        )
        self._open(self._header)

    # -- what subclasses provide -------------------------------------------------

    def _open(self, header: Mapping[str, Any]) -> None:
        """Start the output, with the header facts."""

    def _record(self, event: ExecEvent) -> None:
        raise NotImplementedError

    def _record_samples(self, time: float, values: dict[str, object], pose: Pose2D | None) -> None:
        """Record the state ``values`` written at ``time`` (changed or due) and the pose."""
        raise NotImplementedError

    def _finish(self, end: float | None, count: int) -> None:
        """Write the end record (``end`` is the loop time at close) and close the output."""

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"<{type(self).__name__} {state}, {self._count} events>"


class MemoryRecorder(Recorder):
    """A recorder that keeps the events in memory; `recording` returns them for replay.

    Example:
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
        state_keys: Iterable[str] | None = None,
        sample_rate: float | None = None,
        pose_frame: str | None = "base_link",
        metadata: Mapping[str, object] | None = None,
    ) -> None:
        super().__init__(
            state_keys=state_keys, sample_rate=sample_rate, pose_frame=pose_frame, metadata=metadata
        )
        self.events: list[ExecEvent] = []
        self._series = SeriesBuilder()
        self._end: float | None = None

    def _record(self, event: ExecEvent) -> None:
        self.events.append(event)

    def _record_samples(self, time: float, values: dict[str, object], pose: Pose2D | None) -> None:
        add = self._series.add
        for key, value in values.items():
            add(time, key, value)
        if pose is not None:
            self._series.add_pose(time, *pose)

    def _finish(self, end: float | None, count: int) -> None:
        self._end = end

    def recording(self) -> Recording:
        """The events so far as a `Recording` (complete once the recorder is closed)."""
        header = RecordingHeader.from_json(self._header)
        samples, poses = self._series.build(header.pose_frame)
        return Recording(
            header,
            tuple(self.events),
            end=self._end if self._closed else None,
            samples=samples,
            poses=poses,
        )
