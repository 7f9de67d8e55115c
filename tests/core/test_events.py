"""The typed events (issue 24): one frozen class per kind, and the one codec of their data."""

from __future__ import annotations

import dataclasses
import json

import pytest

import pyrobots_aio
from pyrobots_aio import (
    ActionAbandonment,
    ActionFinished,
    ActionPaused,
    ActionResumed,
    ActionSpawned,
    ActionStarted,
    CancelEscalated,
    CancelRequested,
    EventKind,
    ExecEvent,
    LoopBlocked,
    MonitorFired,
    ResourceAcquired,
    ResourceEvent,
    ResourcePreempted,
    ResourceReleased,
    ResourceSkipped,
    ResourceWaiting,
    StateSampled,
    event_from_data,
    event_type,
)

HELD = (("body",), ("wheels", "arm"), 3)
"""``resources``, ``leaves``, ``priority`` of the resource events below."""

EVENTS: list[tuple[ExecEvent, str]] = [
    (ActionSpawned(0.5, 2, "walk", parent=1), '{"parent":1}'),
    (ActionStarted(0.5, 2, "walk"), "{}"),
    (
        ActionFinished(1.0, 2, "walk", "failed", "ValueError('boom')"),
        '{"outcome":"failed","error":"ValueError(\'boom\')"}',
    ),
    (CancelRequested(1.0, 2, "walk", "stop", None), '{"reason":"stop","by":null}'),
    (CancelEscalated(2.0, 2, "walk", "a.py:3"), '{"location":"a.py:3"}'),
    (ActionAbandonment(3.0, 2, "walk", "a.py:3"), '{"location":"a.py:3"}'),
    (ActionPaused(1.0, 3, "kid", "hold", 4, 2), '{"reason":"hold","by":4,"paused":2}'),
    (ActionResumed(2.0, 3, "kid", 2), '{"resumed":2}'),
    (
        ResourceWaiting(0.0, 2, "walk", *HELD),
        '{"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        ResourceAcquired(0.0, 2, "walk", *HELD),
        '{"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        ResourceAcquired(0.0, 2, "walk", ("body",), ("arm",), 3, given_back=True),
        '{"leaves":["arm"],"given_back":true,"resources":["body"],"priority":3}',
    ),
    (
        ResourceReleased(0.0, 2, "walk", *HELD, withdrawn=True),
        '{"withdrawn":true,"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        ResourceReleased(0.0, 2, "walk", ("body",), ("arm",), 3, lent_to=5),
        '{"leaves":["arm"],"lent_to":5,"resources":["body"],"priority":3}',
    ),
    (
        ResourcePreempted(0.0, 2, "walk", *HELD, "arm", 5, "mine", suspended=True),
        '{"resource":"arm","by":5,"reason":"mine","suspended":true,'
        '"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        ResourceSkipped(0.0, 2, "walk", *HELD, "arm", 5, None),
        '{"busy":"arm","holder":5,"queued":null,'
        '"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        ResourceSkipped(0.0, 2, "walk", *HELD, "arm", 5, deadlock=((2, "arm", 5), (5, "x", 2))),
        '{"busy":"arm","holder":5,"deadlock":[[2,"arm",5],[5,"x",2]],'
        '"resources":["body"],"leaves":["wheels","arm"],"priority":3}',
    ),
    (
        MonitorFired(1.0, None, "bumper becomes=True", 1, "bumper", "becomes=True", True, "none"),
        '{"monitor":1,"var":"bumper","condition":"becomes=True","value":true,"callback":"none"}',
    ),
    (
        LoopBlocked(1.0, None, None, 0.25, 0.1, "task 'main'", None, "  ..."),
        '{"duration":0.25,"threshold":0.1,"blocker":"task \'main\'","location":null,'
        '"stack":"  ..."}',
    ),
    (StateSampled(1.0, None, "v", 0.5), '{"value":0.5}'),
]


def test_every_kind_has_one_frozen_class_that_names_it() -> None:
    classes = {event_type(kind) for kind in EventKind}
    assert len(classes) == len(EventKind)
    for kind in EventKind:
        cls = event_type(kind)
        assert cls.kind is kind
        assert issubclass(cls, ExecEvent)
        assert cls.__dataclass_params__.frozen  # type: ignore[attr-defined]
        assert "__slots__" in cls.__dict__
        assert getattr(pyrobots_aio, cls.__name__) is cls
    assert {type(event) for event, _ in EVENTS} == classes


@pytest.mark.parametrize(("event", "recorded"), EVENTS, ids=lambda e: getattr(e, "kind", ""))
def test_the_data_is_what_recordings_hold_and_reads_back(event: ExecEvent, recorded: str) -> None:
    data = event.data
    assert json.dumps(data, separators=(",", ":")) == recorded  # the keys in the order of v2
    assert event_from_data(event.kind, event.time, event.action, event.name, data) == event
    with pytest.raises(dataclasses.FrozenInstanceError):
        event.time = 9.0  # type: ignore[misc]


def test_an_event_without_leaves_reads_its_resources_as_its_leaves() -> None:
    data = {"resources": ["wheels"], "priority": 2}
    event = event_from_data(EventKind.RESOURCE_ACQUIRED, 0.0, 1, "walk", data)
    assert event == ResourceAcquired(0.0, 1, "walk", ("wheels",), ("wheels",), 2)
    assert isinstance(event, ResourceEvent)


def test_missing_or_mistyped_facts_read_as_their_fallbacks() -> None:
    hostile = {"parent": "x", "outcome": 3, "by": True, "priority": "high", "leaves": "arm"}
    read = [
        event_from_data(kind, 1.0, 1, "a", hostile)
        for kind in (
            EventKind.ACTION_SPAWNED,
            EventKind.ACTION_FINISHED,
            EventKind.CANCEL_REQUESTED,
            EventKind.RESOURCE_RELEASED,
            EventKind.RESOURCE_SKIPPED,
            EventKind.LOOP_BLOCKED,
        )
    ]
    assert read == [
        ActionSpawned(1.0, 1, "a", None),
        ActionFinished(1.0, 1, "a", "not_done", None),
        CancelRequested(1.0, 1, "a", None, None),
        ResourceReleased(1.0, 1, "a", (), (), 0),
        ResourceSkipped(1.0, 1, "a", (), (), 0, "", None),
        LoopBlocked(1.0, 1, "a", 0.0, 0.0, "", None, ""),
    ]
    bad_cycle = {"deadlock": [[1, "a", 2], ["x"], [3, 4, 5]]}
    skipped = event_from_data(EventKind.RESOURCE_SKIPPED, 1.0, 1, "a", bad_cycle)
    assert isinstance(skipped, ResourceSkipped)
    assert skipped.deadlock == ((1, "a", 2),)
