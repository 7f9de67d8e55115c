from __future__ import annotations

import asyncio
import logging
import random
import time
from typing import TYPE_CHECKING, Any

import pytest

from pyrobots_aio._exceptions import UnknownStateKeyError
from pyrobots_aio.loops import run_lockstep
from pyrobots_aio.state import StateSample, StateStore, Subscription

if TYPE_CHECKING:
    from collections.abc import Mapping

SENSORS = {
    "bumper": False,
    "bumper_left": False,
    "bumper_right": False,
    "cliff_left": False,
    "cliff_right": False,
    "docked": True,
    "ir_center": 1.5,
    "ir_left": 1.5,
    "ir_right": 1.5,
    "v": 0.0,
    "w": 0.0,
}


def _store(**values: Any) -> StateStore:
    return StateStore(values, clock=lambda: 0.0)


class Recorder:
    """A subscriber that keeps every notification it gets."""

    def __init__(self, name: str = "rec", log: list[tuple[str, dict[str, Any]]] | None = None):
        self.name = name
        self.calls: list[dict[str, Any]] = []
        self.log = log

    def __call__(self, changes: Mapping[str, Any]) -> None:
        self.calls.append(dict(changes))
        if self.log is not None:
            self.log.append((self.name, dict(changes)))


# -- mapping and attribute access ----------------------------------------------


def test_reads_as_a_mapping_and_by_attribute() -> None:
    store = _store(bumper=True, v=0.25)
    assert store["bumper"] is True
    assert store.bumper is True
    assert store.v == 0.25
    assert "v" in store
    assert "w" not in store
    assert len(store) == 2
    assert list(store) == ["bumper", "v"]
    assert list(store.keys()) == ["bumper", "v"]
    assert dict(store.items()) == {"bumper": True, "v": 0.25}
    assert store == {"bumper": True, "v": 0.25}
    assert store.get("w") is None
    assert store.get("w", 0.0) == 0.0


def test_writes_by_item_attribute_set_and_update() -> None:
    store = _store()
    store["a"] = 1
    store.b = 2
    store.set("c", 3)
    store.update({"d": 4}, e=5)
    store.update([("f", 6)])
    assert dict(store) == {"a": 1, "b": 2, "c": 3, "d": 4, "e": 5, "f": 6}


def test_keys_named_like_store_attributes_use_item_access() -> None:
    store = _store()
    store["update"] = "u"
    store["keys"] = "k"
    store["_hidden"] = "h"
    assert store["update"] == "u"
    assert store["keys"] == "k"
    assert store["_hidden"] == "h"
    assert callable(store.update)  # attribute access finds the method, not the key
    with pytest.raises(AttributeError) as caught:
        store.update = "x"  # type: ignore[method-assign,assignment]
    assert str(caught.value) == (
        "cannot write state key 'update' as an attribute: the name belongs to the store; "
        "write store['update'] = value"
    )
    with pytest.raises(AttributeError) as caught:
        store._hidden = "x"
    assert str(caught.value) == (
        "cannot write state key '_hidden' as an attribute: the name starts with '_'; "
        "write store['_hidden'] = value"
    )
    with pytest.raises(AttributeError) as caught:
        _ = store._hidden
    assert not isinstance(caught.value, UnknownStateKeyError)
    assert str(caught.value) == "'StateStore' object has no attribute '_hidden'"
    assert store["update"] == "u"
    assert len(store) == 3


def test_keys_are_strings_and_never_deleted() -> None:
    store = _store(bumper=False)
    with pytest.raises(TypeError) as caught:
        store[1] = "one"  # type: ignore[index]
    assert str(caught.value) == "state keys are strings, got 1 (int)"
    with pytest.raises(TypeError) as deleting_item:
        del store["bumper"]
    assert str(deleting_item.value) == (
        "cannot delete state key 'bumper': keys are never deleted; write None"
    )
    with pytest.raises(AttributeError) as deleting:
        del store.bumper
    assert str(deleting.value) == "cannot delete 'bumper': state keys are never deleted; write None"
    assert store == {"bumper": False}


def test_dir_lists_identifier_keys() -> None:
    store = _store(bumper=False, **{"ir-left": 1.0, "_raw": 2})
    names = dir(store)
    assert "bumper" in names
    assert "subscribe" in names
    assert "ir-left" not in names
    assert "_raw" not in names


def test_repr_is_short() -> None:
    assert repr(_store(bumper=False, v=0.5)) == (
        "<StateStore 2 keys, version 1: {'bumper': False, 'v': 0.5}>"
    )
    assert repr(StateStore(SENSORS, clock=lambda: 0.0)) == (
        "<StateStore 11 keys, version 1: {'bumper': False, 'bumper_left': False, "
        "'bumper_right': False, 'cliff_left': False, ...}>"
    )


# -- unknown keys ------------------------------------------------------------------


def test_unknown_key_message_names_the_closest_keys() -> None:
    store = StateStore(SENSORS, clock=lambda: 0.0)
    expected = (
        "unknown state key 'bumpr'; closest: ['bumper', 'bumper_left']; known keys: "
        "['bumper', 'bumper_left', 'bumper_right', 'cliff_left', 'cliff_right', 'docked', "
        "'ir_center', 'ir_left'] and 3 more"
    )
    with pytest.raises(UnknownStateKeyError) as by_item:
        _ = store["bumpr"]
    assert str(by_item.value) == expected
    with pytest.raises(UnknownStateKeyError) as by_attribute:
        _ = store.bumpr
    assert str(by_attribute.value) == expected
    assert isinstance(by_item.value, KeyError)
    assert isinstance(by_attribute.value, AttributeError)
    assert not hasattr(store, "bumpr")
    assert getattr(store, "bumpr", "fallback") == "fallback"


def test_unknown_key_message_without_close_match_or_keys() -> None:
    with pytest.raises(UnknownStateKeyError) as caught:
        _ = _store(v=0.0, w=0.0).sample("battery")
    assert str(caught.value) == "unknown state key 'battery'; closest: []; known keys: ['v', 'w']"
    with pytest.raises(UnknownStateKeyError) as empty:
        _ = StateStore().bumper
    assert str(empty.value) == (
        "unknown state key 'bumper'; the state is empty (nothing has written it yet)"
    )


def test_require_checks_that_keys_exist() -> None:
    store = _store(bumper=False, docked=True)
    store.require("bumper", "docked")
    with pytest.raises(UnknownStateKeyError) as caught:
        store.require("bumper", "dockd", "nope")
    assert str(caught.value) == (
        "unknown state key 'dockd'; closest: ['docked']; known keys: ['bumper', 'docked']"
    )


# -- timestamps and versions ---------------------------------------------------------


def test_timestamps_come_from_the_loop_clock() -> None:
    async def main() -> tuple[StateSample, StateSample, float, float]:
        store = StateStore()
        store.bumper = False
        first = store.sample("bumper")
        await asyncio.sleep(1.5)
        store.bumper = True
        store.update(v=0.1, w=0.2)
        await asyncio.sleep(0.25)
        return first, store.sample("bumper"), store.timestamp("v"), store.timestamp("w")

    first, second, v_stamp, w_stamp = run_lockstep(main)
    assert first == StateSample(value=False, timestamp=0.0, version=1)
    assert second == StateSample(value=True, timestamp=1.5, version=2)
    assert (v_stamp, w_stamp) == (1.5, 1.5)


def test_without_a_running_loop_timestamps_use_the_monotonic_clock() -> None:
    store = StateStore()
    before = time.monotonic()
    store.bumper = False
    after = time.monotonic()
    assert before <= store.timestamp("bumper") <= after


def test_the_clock_is_injectable() -> None:
    now = [10.0]
    store = StateStore(clock=lambda: now[0])
    store.a = 1
    now[0] = 12.5
    store.update(a=2, b=3)
    assert store.timestamp("a") == 12.5
    assert store.sample("b") == StateSample(3, 12.5, 1)


def test_versions_count_writes_per_key_and_per_operation() -> None:
    store = StateStore({"a": 0, "b": 0}, clock=lambda: 0.0)
    assert (store.version("a"), store.version("b"), store.version()) == (1, 1, 1)
    store.a = 1
    store.a = 1  # the same value is still a write
    store.update(a=2, b=2)
    store.update()  # writing nothing does nothing
    assert (store.version("a"), store.version("b"), store.version()) == (4, 2, 4)
    with pytest.raises(UnknownStateKeyError):
        store.version("c")
    with pytest.raises(UnknownStateKeyError):
        store.timestamp("c")


def test_versions_and_timestamps_follow_interleaved_single_and_batch_writes() -> None:
    # Batches of a key sequence seen before are counted once per write, not per key:
    # whichever way a key was written, its version counts every write and its
    # timestamp is its latest write's.
    now = [0.0]
    store = StateStore(clock=lambda: now[0])
    writes = {"a": 0, "b": 0, "c": 0}
    stamps: dict[str, float] = {}
    plan: list[dict[str, int]] = [{"a": 1, "b": 1}, {"b": 2}, {"a": 3, "b": 3}, {"c": 4}]
    plan += [{"b": 5, "a": 5}, {"a": 6, "b": 6}, {"a": 7}, {"a": 8, "b": 8, "c": 8}]
    for step, values in enumerate(plan * 3):
        now[0] = float(step)
        if len(values) == 1:
            ((key, value),) = values.items()
            store[key] = value
        else:
            store.update(values)
        for key in values:
            writes[key] += 1
            stamps[key] = now[0]
        for key in store:
            assert store.sample(key) == StateSample(store[key], stamps[key], writes[key])
            assert (store.timestamp(key), store.version(key)) == (stamps[key], writes[key])
    assert store.version() == len(plan) * 3


def test_versions_and_timestamps_stay_exact_over_many_key_sequences() -> None:
    now = [0.0]
    store = StateStore(clock=lambda: now[0])
    keys = [f"k{i}" for i in range(12)]
    writes = dict.fromkeys(keys, 0)
    stamps = dict.fromkeys(keys, 0.0)
    rng = random.Random(0)
    sequences = list(dict.fromkeys(tuple(rng.sample(keys, rng.randint(2, 5))) for _ in range(110)))
    sequences = sequences[:100]
    assert len(sequences) == 100  # more than the store counts as a whole
    for step in range(400):  # each sequence written a few times, in between the others
        now[0] = step / 10
        chosen = sequences[rng.randrange(100)] if step % 3 else sequences[step % 100]
        store.update(dict.fromkeys(chosen, step))
        if step % 7 == 0:
            store.set(chosen[0], -step)
        for key in (*chosen, chosen[0]) if step % 7 == 0 else chosen:
            writes[key] += 1
            stamps[key] = now[0]
        if step % 50 == 49:
            assert {key: store.version(key) for key in keys} == writes
            assert {key: store.timestamp(key) for key in keys} == stamps


# -- change notification ------------------------------------------------------------


def test_every_write_is_seen_even_within_one_loop_iteration() -> None:
    async def main() -> list[dict[str, Any]]:
        store = StateStore({"bumper": False})
        seen = Recorder()
        store.subscribe(seen, "bumper")
        loop = asyncio.get_running_loop()
        loop.call_soon(store.set, "bumper", True)  # a 20 ms pulse would look like this
        loop.call_soon(store.set, "bumper", False)
        await asyncio.sleep(0)
        return seen.calls

    assert run_lockstep(main) == [{"bumper": True}, {"bumper": False}]


def test_batch_update_notifies_each_subscriber_once_with_its_keys() -> None:
    store = _store(a=0, b=0, c=0)
    every, some, other = Recorder(), Recorder(), Recorder()
    store.subscribe(every)
    store.subscribe(some, keys=["a", "c"])
    store.subscribe(other, keys="z")
    store.update(a=1, b=2, c=3)
    assert every.calls == [{"a": 1, "b": 2, "c": 3}]
    assert some.calls == [{"a": 1, "c": 3}]
    assert other.calls == []


def test_write_owned_is_a_batch_update_of_the_dict_given_up() -> None:
    store = _store(a=0, b=0)
    every, some = Recorder(), Recorder()
    store.subscribe(every)
    store.subscribe(some, keys="b")
    version = store.version()
    store.write_owned({})  # nothing written
    assert store.version() == version
    store.write_owned({"a": 1, "b": 2, "new": 3})
    assert (store.a, store.b, store.new, store.version()) == (1, 2, 3, version + 1)
    assert every.calls == [{"a": 1, "b": 2, "new": 3}]
    assert some.calls == [{"b": 2}]
    assert store.timestamp("a") == store.timestamp("new")
    with pytest.raises(TypeError, match="state keys are strings, got 1"):
        store.write_owned({1: "one"})  # type: ignore[dict-item]
    assert 1 not in dict(store)  # nothing of a refused write is kept
    assert store.version() == version + 1
    for bad in (None, [("a", 5)], {"a": 5}.items()):
        with pytest.raises(TypeError, match=r"write_owned takes a dict .* use store\.update"):
            store.write_owned(bad)  # type: ignore[arg-type]
    assert (store.a, store.version()) == (1, version + 1)


def test_per_key_subscription_sees_only_its_keys() -> None:
    store = _store()
    bumper = Recorder()
    sub = store.subscribe(bumper, "bumper")
    store.v = 0.1
    store.bumper = True
    store.w = 0.2
    store.update(v=0.3, w=0.4)
    assert bumper.calls == [{"bumper": True}]
    assert sub.keys == frozenset({"bumper"})
    assert store.subscribe(Recorder()).keys is None


def test_subscribers_run_every_key_first_then_in_subscription_order() -> None:
    store = _store()
    log: list[tuple[str, dict[str, Any]]] = []
    store.subscribe(Recorder("keyed-1", log), ["a", "b"])
    store.subscribe(Recorder("every", log))
    store.subscribe(Recorder("keyed-2", log), "a")
    store.a = 1
    store.update(b=2, a=3)
    assert log == [
        ("every", {"a": 1}),
        ("keyed-1", {"a": 1}),
        ("keyed-2", {"a": 1}),
        ("every", {"b": 2, "a": 3}),
        ("keyed-1", {"b": 2, "a": 3}),
        ("keyed-2", {"a": 3}),
    ]


def test_changes_are_read_only() -> None:
    store = _store()
    errors: list[Exception] = []

    def meddle(changes: Mapping[str, Any]) -> None:
        try:
            changes["a"] = "meddled"  # type: ignore[index]
        except TypeError as exc:
            errors.append(exc)

    store.subscribe(meddle)
    store.a = 1
    assert len(errors) == 1
    assert store.a == 1


def test_a_failing_subscriber_is_logged_and_the_others_still_run(
    caplog: pytest.LogCaptureFixture,
) -> None:
    store = _store(bumper=False)

    def boom(changes: Mapping[str, Any]) -> None:
        raise RuntimeError("subscriber bug")

    first, last = Recorder(), Recorder()
    store.subscribe(first)
    failing = store.subscribe(boom, "bumper")
    store.subscribe(last, "bumper")
    with caplog.at_level(logging.ERROR, logger="pyrobots_aio.state"):
        store.bumper = True
    assert first.calls == last.calls == [{"bumper": True}]
    assert store.sample("bumper") == StateSample(True, 0.0, 2)
    [record] = caplog.records
    assert record.name == "pyrobots_aio.state"
    assert record.getMessage() == f"state subscriber {failing!r} failed on a write of ['bumper']"
    assert record.exc_info is not None
    assert str(record.exc_info[1]) == "subscriber bug"


def test_writing_an_unchanged_value_is_a_write() -> None:
    # Not skipped as "no change": a level condition with max_firing_freq=0 fires on every
    # write that finds it true, and versions and timestamps count writes (DESIGN.md §5).
    now = [0.0]
    store = StateStore({"bumper": True, "v": 0.0}, clock=lambda: now[0])
    seen = Recorder()
    store.subscribe(seen, "bumper")
    for tick in range(1, 4):
        now[0] = tick / 50
        store.update(bumper=True, v=0.0)
    store.bumper = True
    assert seen.calls == [{"bumper": True}] * 4
    assert store.sample("bumper") == StateSample(True, 0.06, 5)
    assert store.sample("v") == StateSample(0.0, 0.06, 4)


def test_the_same_batch_written_again_reaches_the_subscribers_of_the_moment() -> None:
    # A backend writes the same key sequence every tick; who hears it changes in between.
    store = _store(a=0, b=0, c=0)
    first, late, every = Recorder(), Recorder(), Recorder()
    early = store.subscribe(first, ["a", "c"])
    store.update(a=1, b=1, c=1)
    store.subscribe(late, "b")
    store.update(a=2, b=2, c=2)
    early.close()
    watching_all = store.subscribe(every)
    store.update(a=3, b=3, c=3)
    watching_all.close()
    store.update(a=4, b=4, c=4)
    store.update(c=5, b=5, a=5)  # another order is another sequence
    assert first.calls == [{"a": 1, "c": 1}, {"a": 2, "c": 2}]
    assert late.calls == [{"b": 2}, {"b": 3}, {"b": 4}, {"b": 5}]
    assert every.calls == [{"a": 3, "b": 3, "c": 3}]


def test_unsubscribing_during_notification_takes_effect_at_once() -> None:
    store = _store()
    later = Recorder()
    subs: dict[str, Subscription] = {}

    def closer(changes: Mapping[str, Any]) -> None:
        subs["later"].close()
        subs["closer"].close()

    subs["closer"] = store.subscribe(closer)
    subs["later"] = store.subscribe(later)
    store.a = 1
    store.a = 2
    assert later.calls == []
    assert subs["closer"].closed
    assert subs["later"].closed


def test_subscribing_during_notification_starts_with_the_next_write() -> None:
    store = _store()
    added = Recorder()

    def adder(changes: Mapping[str, Any]) -> None:
        if changes["a"] == 1:
            store.subscribe(added, "a")

    store.subscribe(adder, "a")
    store.a = 1
    store.a = 2
    assert added.calls == [{"a": 2}]


def test_writes_made_by_subscribers_are_seen_in_order() -> None:
    store = _store()
    log: list[tuple[str, dict[str, Any]]] = []

    def derive(changes: Mapping[str, Any]) -> None:
        if "ir" in changes:
            store.near = changes["ir"] < 0.5

    store.subscribe(derive)
    store.subscribe(Recorder("monitor", log))
    store.ir = 0.3
    assert log == [("monitor", {"ir": 0.3}), ("monitor", {"near": True})]
    assert store.near is True


def test_subscription_closes_as_a_context_manager_and_has_a_repr() -> None:
    store = _store()
    seen = Recorder()
    with store.subscribe(seen, ["b", "a"]) as sub:
        store.a = 1
        assert repr(sub) == "<Subscription Recorder keys=['a', 'b']>"
    store.a = 2
    sub.close()  # closing twice is harmless
    assert seen.calls == [{"a": 1}]
    assert repr(sub) == "<Subscription Recorder keys=['a', 'b'] closed>"

    def on_any(changes: Mapping[str, Any]) -> None:
        pass

    every = store.subscribe(on_any)
    assert repr(every) == (
        "<Subscription test_subscription_closes_as_a_context_manager_and_has_a_repr"
        ".<locals>.on_any every key>"
    )


def test_subscribe_rejects_empty_or_non_string_keys() -> None:
    store = _store()
    with pytest.raises(ValueError, match=r"^keys is empty: pass None to watch every key$"):
        store.subscribe(Recorder(), [])
    with pytest.raises(TypeError, match=r"^state keys are strings, got 3 \(int\)$"):
        store.subscribe(Recorder(), [3])  # type: ignore[list-item]


# -- read tracking ----------------------------------------------------------------------


def test_track_reads_records_exactly_the_keys_read() -> None:
    store = StateStore(SENSORS, clock=lambda: 0.0)
    with store.track_reads() as reads:
        _ = store["bumper"]
        _ = store.docked
        _ = store.get("battery")  # missing keys count: writing them may change the result
        _ = store.sample("ir_left")
        _ = store.timestamp("ir_right")
        _ = store.version("v")
        _ = "cliff_left" in store
        _ = store.version()
        _ = list(store)
        _ = len(store)
        store.require("w")
        store.w = 1.0
    assert reads == {"bumper", "docked", "battery", "ir_left", "ir_right", "v", "cliff_left"}
    _ = store.ir_center  # after the block: not recorded
    assert "ir_center" not in reads


def test_track_reads_nests_and_keeps_stores_apart() -> None:
    robot, other = _store(a=1, b=2), _store(a=1, c=3)
    with robot.track_reads() as outer:
        _ = robot.a
        with robot.track_reads() as inner:
            _ = robot.b
            _ = other.c
        with other.track_reads() as on_other:
            _ = other.a
            _ = robot.b
    assert outer == {"a", "b"}
    assert inner == {"b"}
    assert on_other == {"a"}


def test_track_reads_in_async_code_is_isolated_between_tasks() -> None:
    async def main() -> tuple[set[str], set[str]]:
        store = StateStore(SENSORS)

        async def predicate(keys: list[str]) -> set[str]:
            with store.track_reads() as reads:
                for key in keys:
                    _ = store[key]
                    await asyncio.sleep(0.01)  # let the other tasks read meanwhile
            return set(reads)

        async def untracked_reader() -> None:
            for _ in range(5):
                _ = store.v
                await asyncio.sleep(0.005)

        async with asyncio.TaskGroup() as tg:
            first = tg.create_task(predicate(["bumper", "ir_left"]))
            second = tg.create_task(predicate(["docked", "cliff_left", "w"]))
            tg.create_task(untracked_reader())
        return first.result(), second.result()

    assert run_lockstep(main) == ({"bumper", "ir_left"}, {"docked", "cliff_left", "w"})


# -- filtered ---------------------------------------------------------------------------------


def test_filtered_returns_the_moving_average() -> None:
    store = StateStore()
    means = [store.filtered("ir", float(v)) for v in range(1, 13)]
    assert means[:3] == [1.0, 1.5, 2.0]
    assert means[9] == 5.5  # mean of 1..10
    assert means[11] == 7.5  # mean of 3..12: the default window is 10
    assert store.filtered("ir", 0.0, window=2) == 6.0  # resized: 12 and 0 remain
    assert "ir" not in store


def test_filtered_windows_belong_to_one_store() -> None:
    first, second = StateStore(), StateStore()
    assert first.filtered("v", 1.0, window=3) == 1.0
    assert first.filtered("v", 2.0, window=3) == 1.5
    assert second.filtered("v", 10.0, window=3) == 10.0
    assert first.filtered("w", 4.0, window=3) == 4.0


def test_filtered_rejects_a_bad_window() -> None:
    store = StateStore()
    with pytest.raises(ValueError, match=r"^window must be a positive integer, got 0$"):
        store.filtered("ir", 1.0, window=0)
    store.filtered("ir", 1.0, window=3)
    with pytest.raises(ValueError, match=r"^window must be a positive integer, got 2.5$"):
        store.filtered("ir", 1.0, window=2.5)  # type: ignore[arg-type]
