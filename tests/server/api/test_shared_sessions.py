"""`lumipose serve --redis URL`: two real servers on one real redis-server take turns on a device's walk
and answer as one server; Redis stopped is a 503 naming it and a degraded /healthz (200), never a 500."""

import subprocess
import sys
import uuid

import numpy as np
import pytest

from lumipose_client import Client, LumiposeError
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures
from server.redis_store import describe
from simulator.local_server import LocalServer
from tests.helpers import ROOM, dark_frame
from tests.redis_server import RedisServer
from shared_schemas import FrameKind


def _upload(client: Client, frame, device: str | None, map_name: str):
    return client.locate(np.ascontiguousarray(frame.pixels).tobytes(), frame.meta, map=map_name, compress=None,
                         **({"device": device} if device else {}))


def _answer(result) -> dict:
    return result.model_dump(mode="json", exclude={"timing_ms"})


def test_two_servers_on_one_redis_answer_a_walk_as_one_server(redis_url):
    config = OfficeConfig(walk="zigzag", max_captures=6, pose_scale=0.25, seed=3)
    beacon_map = office_scenes(config)[0].beacon_map()
    device = f"phone-{uuid.uuid4().hex[:6]}"
    with (LocalServer("--redis", redis_url, "--log-level", "warning") as first,
          LocalServer("--redis", redis_url, "--log-level", "warning") as second,
          LocalServer("--log-level", "warning") as alone,
          Client(first.url) as a, Client(second.url) as b, Client(alone.url) as one):
        for client in (a, b, one):
            client.put_map(beacon_map)
        shared, expected = [], []
        for capture in walk_captures(config):
            for frame in (*capture.id_frames, capture.pose_frame):
                # alternate the replicas frame by frame: the ID frames kept by one reach the other's pose frame
                shared.append(_upload((a, b)[len(shared) % 2], frame, device, beacon_map.name))
                expected.append(_upload(one, frame, device, beacon_map.name))
        assert a.health().status == "ok" and a.health().unavailable == []
    assert [_answer(r) for r in shared] == [_answer(r) for r in expected]
    fixes = [r for r in shared if r.ok]
    assert len(fixes) >= 3 and all(r.track is not None for r in fixes)
    assert sum(r.beacon_id_source.value == "vlc" for r in fixes) >= 2
    for server in (first, second):
        assert "Traceback" not in server.log(), server.log()


def test_redis_stopped_is_a_503_naming_it_and_a_degraded_health():
    with RedisServer() as redis_server, LocalServer("--redis", redis_server.url, "--log-level", "warning") as server:
        with Client(server.url) as client:
            client.put_map(ROOM)
            assert _upload(client, dark_frame(FrameKind.id, 0.0), "p", ROOM.name).message.endswith("(1 waiting)")
            redis_server.stop()
            with pytest.raises(LumiposeError) as refused:
                _upload(client, dark_frame(FrameKind.id, 0.01), "p", ROOM.name)
            # the frame's map is read from Redis first (maps live there too with --redis): the maps' 503 answers;
            # the sessions' own 503 (the same code) is tested in tests/server/tracking/test_shared.py
            assert refused.value.status == 503 and refused.value.body.error == "redis_unavailable"
            assert "Redis at 127.0.0.1:" in refused.value.body.message
            health = client.health()
            assert health.status == "degraded"
            assert [p.split(": ")[0] for p in health.unavailable] == ["maps", "device sessions"]
            assert f"{describe(redis_server.url)} does not answer" in health.unavailable[1]
    assert "Traceback" not in server.log(), server.log()


@pytest.mark.parametrize("url", ["http://127.0.0.1:6379", "127.0.0.1:6379"])
def test_a_url_that_is_not_redis_stops_the_server_with_a_clear_message(url, tmp_path):
    run = subprocess.run([sys.executable, "-m", "lumipose_cli", "serve", "--redis", url, "--data-dir", str(tmp_path)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2, run.stderr
    assert "redis" in run.stderr and "redis://, rediss://, unix://" in run.stderr, run.stderr
