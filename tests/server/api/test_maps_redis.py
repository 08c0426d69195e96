"""Two real `lumipose serve --redis URL` replicas (own data folders) on one real redis-server: a map
stored, activated or deleted through one is, at once, what the other lists, serves and locates with."""

from __future__ import annotations

import time

import pytest
import redis

from lumipose_client import Client, LumiposeError
from server.redis_store import MAPS_KEY
from shared_schemas import BeaconMap, load_map
from simulator.local_server import LocalServer
from tests.conftest import API_KEY

DEMO = load_map()


def _room(name: str, shift_m: float) -> BeaconMap:
    """The demo map under another name, its panel `shift_m` along +X."""
    data = DEMO.model_dump(mode="json", by_alias=True)
    data["name"], data["beacons"][0]["center_m"] = name, [shift_m, 0.0, 1.0]
    return BeaconMap.model_validate(data)


@pytest.fixture(scope="module")
def replicas(redis_server, tmp_path_factory):
    """Two replicas started as a deployment starts them: the same --redis and the same --map file."""
    if redis_server.process is None:
        redis_server.start()
    with redis.Redis.from_url(redis_server.url) as store:
        store.flushall()
    startup = tmp_path_factory.mktemp("maps") / "lab.json"
    startup.write_text(_room("lab", 2.0).model_dump_json(by_alias=True))
    args = ("--redis", redis_server.url, "--map", str(startup), "--api-key", API_KEY, "--log-level", "warning")
    with (LocalServer(*args, data_dir=tmp_path_factory.mktemp("a")) as first,
          LocalServer(*args, data_dir=tmp_path_factory.mktemp("b")) as second):
        with Client(first.url, api_key=API_KEY) as one, Client(second.url, api_key=API_KEY) as other:
            yield one, other
        for server in (first, second):
            assert "Traceback" not in server.log(), server.log()
        assert not list(first.data_dir.glob("maps/*")) and not (first.data_dir / "active_map.json").exists()


def _refusal(call, *args) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call(*args)
    return refused.value


def _x_m(client: Client, fixture_frame, map_name: str | None = None) -> float:
    meta, frame = fixture_frame
    result = client.locate(frame, meta, map=map_name)
    assert result.ok, result
    return result.position_m[0]


def test_the_startup_map_is_active_on_both_and_cannot_be_deleted(replicas):
    one, other = replicas
    assert one.active_map().name == other.active_map().name == "lab"
    assert _refusal(other.delete_map, "lab").body.error == "active_map"


def test_a_map_put_through_one_replica_is_listed_got_and_located_with_on_the_other(replicas, fixture_frame):
    one, other = replicas
    one.put_map(_room("shifted", 1.0))
    assert {m.name: m.source for m in other.maps()} == {"test-bench": "bundled", "lab": "startup", "shifted": "stored"}
    assert other.get_map("shifted") == _room("shifted", 1.0)
    bench_x = _x_m(other, fixture_frame, "test-bench")
    assert _x_m(other, fixture_frame, "shifted") == pytest.approx(bench_x + 1.0, abs=1e-6)

    one.set_active_map("shifted")  # activation on one is the active map of the other
    assert other.active_map().name == "shifted"
    assert _x_m(other, fixture_frame) == pytest.approx(bench_x + 1.0, abs=1e-6)
    assert _refusal(one.delete_map, "shifted").body.error == "active_map"

    other.set_active_map("lab")
    one.delete_map("shifted")
    refusal = _refusal(other.get_map, "shifted")
    assert (refusal.status, refusal.body.error) == (404, "not_found")
    assert _x_m(other, fixture_frame) == pytest.approx(bench_x + 2.0, abs=1e-6)  # the startup map again


def test_a_damaged_value_is_named_by_healthz_and_refused_with_409(replicas, redis_server):
    one, other = replicas
    with redis.Redis.from_url(redis_server.url) as store:
        store.hset(MAPS_KEY, "hand-written", b"not a map")
    health = other.health()
    assert (health.status, health.damaged) == ("degraded", ["redis:lumipose:maps/hand-written"])
    refusal = _refusal(one.get_map, "hand-written")
    assert (refusal.status, refusal.body.error, refusal.body.field) == (409, "damaged_map", "name")
    assert "redis:lumipose:maps/hand-written" in refusal.body.message
    one.delete_map("hand-written")
    assert other.health().status == "ok"


def test_redis_stopped_is_a_503_naming_redis_never_a_500_or_a_hang(replicas, redis_server, fixture_frame):
    one, other = replicas
    meta, frame = fixture_frame
    redis_server.stop()
    try:
        for call, args in ((other.maps, ()), (other.active_map, ()), (other.get_map, ("lab",)),
                           (one.put_map, (_room("x", 1.0),)), (one.set_active_map, ("lab",)),
                           (one.delete_map, ("x",)), (other.locate, (frame, meta))):
            started = time.monotonic()
            refusal = _refusal(call, *args)
            assert time.monotonic() - started < 3.0, call
            assert (refusal.status, refusal.body.error) == (503, "redis_unavailable"), call
            assert f"Redis at 127.0.0.1:{redis_server.port}/0 cannot be reached" in refusal.body.message
        health = other.health()  # 200: the process runs (a liveness probe must not restart it), Redis named
        assert health.status == "degraded" and f"Redis at 127.0.0.1:{redis_server.port}/0" in health.unavailable[0]
    finally:
        redis_server.start()
    assert other.active_map().name == "lab"  # back, on a new connection (this Redis kept nothing: --save "")
