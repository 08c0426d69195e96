"""Maps and the active map in a real redis-server (server/redis_store.py): two stores on one Redis are
two replicas; what one writes the other reads at once, and the rules are the data folder's."""

from __future__ import annotations

import threading
import time

import pytest
import redis

from server.redis_store import ACTIVE_KEY, MAPS_KEY, RedisMaps, describe
from server.store import MapStore, StoreError
from shared_schemas import BeaconMap, load_map

DEMO = load_map()


def _room(name: str, shift_m: float = 1.0) -> BeaconMap:
    """The demo map under another name, its panel `shift_m` along +X."""
    data = DEMO.model_dump(mode="json", by_alias=True)
    data["name"], data["beacons"][0]["center_m"] = name, [shift_m, 0.0, 1.0]
    return BeaconMap.model_validate(data)


def _replica(url: str, tmp_path, startup=None) -> MapStore:
    return MapStore(tmp_path / "unused", startup, RedisMaps.from_url(url))


@pytest.fixture
def replicas(redis_url, tmp_path):
    return _replica(redis_url, tmp_path), _replica(redis_url, tmp_path)


def _refused(call, *args) -> StoreError:
    with pytest.raises(StoreError) as refused:
        call(*args)
    return refused.value


def test_a_map_stored_through_one_replica_is_listed_got_activated_and_deleted_on_the_other(replicas, tmp_path):
    first, second = replicas
    first.put("office", _room("office"))
    assert second.get("office") == _room("office")
    assert {(s.name, s.source, s.active) for s in second.summaries()} == {
        ("test-bench", "bundled", True), ("office", "stored", False)}
    second.set_active("office")
    assert first.active_name() == "office"
    assert _refused(first.delete, "office").code == "active_map"
    first.set_active("test-bench")
    second.delete("office")
    assert _refused(first.get, "office").code == "not_found"
    assert _refused(second.delete, "test-bench").code == "active_map"  # the bundled map, active again
    assert not (tmp_path / "unused").exists()  # nothing of the maps goes to the data folder


def test_the_startup_map_is_each_replicas_own_and_cannot_be_deleted(redis_url, tmp_path):
    startup = tmp_path / "lab.json"
    startup.write_text(_room("lab", 2.0).model_dump_json(by_alias=True))
    first, second = _replica(redis_url, tmp_path, startup), _replica(redis_url, tmp_path, startup)
    assert first.active_name() == second.active_name() == "lab"
    assert _refused(second.delete, "lab").code == "active_map"
    first.set_active("test-bench")
    assert _refused(second.delete, "lab").code == "fixed_map"
    first.put("lab", _room("lab", 3.0))  # a stored map hides the startup map of its name, as in the data folder
    assert second.get("lab").beacons[0].center_m[0] == 3.0
    second.delete("lab")
    assert first.get("lab").beacons[0].center_m[0] == 2.0


def test_junk_written_into_redis_is_damaged_as_a_damaged_file_is(redis_url, replicas):
    first, second = replicas
    first.put("office", _room("office"))
    first.set_active("office")
    with redis.Redis.from_url(redis_url) as client:
        client.hset(MAPS_KEY, "office", b'{"schema": "lumipose.map/1", "na')
        client.hset(MAPS_KEY, "bad name!", b"never listed")
    refusal = _refused(second.get, "office")
    assert (refusal.code, refusal.field) == ("damaged_map", "name")
    assert "redis:lumipose:maps/office" in refusal.message and "PUT the map again" in refusal.message
    assert second.damaged() == ["redis:lumipose:maps/office"]
    assert [s.name for s in second.summaries()] == ["test-bench"]
    assert second.active_name() == "office"  # named, though damaged: locate says damaged_map rather than another map
    second.set_active("test-bench")
    second.delete("office")  # a damaged map can be deleted
    assert second.damaged() == []
    with redis.Redis.from_url(redis_url) as client:
        client.set(ACTIVE_KEY, b"\xff junk")
    assert first.active_name() == "test-bench"
    assert first.damaged() == ["redis:lumipose:active_map"]


def test_redis_down_is_said_at_once_by_name(redis_server, redis_url, tmp_path):
    store = _replica(redis_url, tmp_path)
    store.put("office", _room("office"))
    redis_server.stop()
    try:
        for call, args in ((store.get, ("office",)), (store.active_name, ()), (store.put, ("x", _room("x"))),
                           (store.set_active, ("office",)), (store.delete, ("office",)), (store.damaged, ())):
            started = time.monotonic()
            refusal = _refused(call, *args)
            assert time.monotonic() - started < 2.0, call
            assert refusal.code == "redis_unavailable"
            assert f"Redis at 127.0.0.1:{redis_server.port}/0 cannot be reached" in refusal.message
        _replica(redis_url, tmp_path)  # a replica starts without Redis (and answers 503 until it is back)
    finally:
        redis_server.start()
    assert store.active_name() == "test-bench"  # a new connection once Redis is back (its data is gone: no --save)


def test_activating_and_deleting_at_once_on_two_replicas_never_leaves_an_active_name_without_its_map(
    redis_url, replicas
):
    activating, deleting = replicas
    names = [f"room-{i}" for i in range(4)]
    stop = threading.Event()
    orphans: list[str] = []
    errors: list[BaseException] = []

    def churn(step) -> None:
        try:
            while not stop.is_set():
                for name in names:
                    step(name)
        except BaseException as error:  # noqa: BLE001 - reported by the test below
            errors.append(error)
            stop.set()

    def activate(name: str) -> None:
        activating.put(name, _room(name))
        try:
            activating.set_active(name)
        except StoreError as error:
            assert error.code == "not_found"  # deleted between the put and the activation

    def delete(name: str) -> None:
        try:
            deleting.delete(name)
        except StoreError as error:
            assert error.code in ("active_map", "not_found")

    def watch_redis() -> None:
        with redis.Redis.from_url(redis_url) as client:
            while not stop.is_set():
                with client.pipeline(transaction=True) as both:  # read at one instant
                    active, maps = both.get(ACTIVE_KEY).hkeys(MAPS_KEY).execute()
                if active is not None and active not in maps and active.decode() != "test-bench":
                    orphans.append(active.decode())

    threads = [threading.Thread(target=churn, args=(activate,)), threading.Thread(target=churn, args=(delete,)),
               threading.Thread(target=watch_redis)]
    for thread in threads:
        thread.start()
    time.sleep(3.0)
    stop.set()
    for thread in threads:
        thread.join(timeout=10)
    assert not errors, errors
    assert not orphans, f"the active name without its map {len(orphans)} times: {orphans[:5]}"
    assert activating.active_name() in set(names) | {"test-bench"}


def test_messages_name_redis_without_its_password():
    assert describe("redis://:secret@cache:6380/2") == "Redis at cache:6380/2"
    assert describe("redis://localhost") == "Redis at localhost:6379/0"
    assert describe("unix:///run/redis.sock?db=1") == "Redis at /run/redis.sock"
