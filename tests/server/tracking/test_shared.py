"""SharedDevices: device sessions in a real redis-server (tests/redis_server.py), shared by "replicas"
(several SharedDevices on one Redis): the same answers as `Devices`, no lost update, expiry, Redis away."""

import json
import random
import socket
import sys
import threading
import time
import uuid

import pytest
import redis

from server.options import LocateOptions
from server.tracking import shared
from server.tracking.devices import DeviceRules, Devices, SessionStoreError
from server import redis_store
from server.redis_store import describe
from server.tracking.shared import SharedDevices
from server.tracking.state import load_device
from shared_schemas import FrameKind
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures
from tests.helpers import answer_without_timings, walk_frames, ROOM, dark_frame
from tests.redis_server import RedisServer

OPTIONS = LocateOptions()


@pytest.fixture(scope="module")
def walk():
    config = OfficeConfig(walk="zigzag", max_captures=6, pose_scale=0.25, seed=3)
    pose_scene, _ = office_scenes(config)
    return pose_scene.beacon_map(), list(walk_captures(config))


@pytest.fixture
def prefix() -> str:
    """Each test's own keys on the session's Redis."""
    return f"test-{uuid.uuid4().hex[:8]}:"


def _stored(client: redis.Redis, devices: SharedDevices, device: str, beacon_map):
    return load_device(client.get(devices.key(device)), beacon_map, OPTIONS.session)


def test_a_walk_in_redis_answers_as_in_memory(walk, redis_url, prefix):
    beacon_map, captures = walk
    memory, stored = Devices(), SharedDevices.from_url(redis_url, prefix=prefix)
    fixes = 0
    for frame in walk_frames(captures):
        expected = memory.locate("phone", frame, beacon_map)
        got = stored.locate("phone", frame, beacon_map)
        assert answer_without_timings(got) == answer_without_timings(expected)
        fixes += got.ok
    assert fixes >= 4
    session, waiting = _stored(redis.Redis.from_url(redis_url), stored, "phone", beacon_map)
    assert session.track.fixes == memory.stats("phone").fixes and not waiting
    assert stored.conflicts == 0


def test_two_replicas_taking_turns_answer_as_one_process(walk, redis_url, prefix):
    """Frames alternate between two stores: an ID frame kept by one is used by the other's pose frame,
    and the track each writes is the one the other reads."""
    beacon_map, captures = walk
    memory = Devices()
    replicas = [SharedDevices.from_url(redis_url, prefix=prefix) for _ in range(2)]
    vlc_ids = 0
    for n, frame in enumerate(walk_frames(captures)):
        expected = memory.locate("phone", frame, beacon_map)
        got = replicas[n % 2].locate("phone", frame, beacon_map)
        assert answer_without_timings(got) == answer_without_timings(expected)
        vlc_ids += got.ok and got.beacon_id_source.value == "vlc"
    assert vlc_ids >= 2  # pose frames named by ID frames that went through the other replica


def test_many_threads_on_two_replicas_lose_no_update(redis_url, prefix):
    """Threads send pose frames of the same devices through two stores at once: every frame counts in
    its device's stored session (conflicting updates retried, none lost), none fails."""
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)  # switch threads often, so the updates interleave
    replicas = [SharedDevices.from_url(redis_url, prefix=prefix) for _ in range(2)]
    threads, devices, frames_each = 8, 8, 5
    errors: list[str] = []

    def send(thread: int) -> None:
        order = [d for d in range(devices) for _ in range(frames_each)]
        random.Random(thread).shuffle(order)
        for n, device in enumerate(order):
            try:
                replicas[(thread + n) % 2].locate(f"phone-{device}", dark_frame(FrameKind.pose, n), ROOM)
            except Exception as error:  # noqa: BLE001 - every failure is counted, not just the first
                errors.append(repr(error))

    try:
        workers = [threading.Thread(target=send, args=(t,)) for t in range(threads)]
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
    finally:
        sys.setswitchinterval(interval)
    assert errors == []
    client = redis.Redis.from_url(redis_url)
    captures = [_stored(client, replicas[0], f"phone-{d}", ROOM)[0].captures for d in range(devices)]
    assert captures == [threads * frames_each] * devices
    conflicts = sum(r.conflicts for r in replicas)
    print(f"{threads * devices * frames_each} updates, {conflicts} retried after a conflict")
    assert conflicts > 0  # the threads did collide, and the retries made up for it


def test_a_silent_device_expires_after_idle_s(redis_url, prefix):
    devices = SharedDevices.from_url(redis_url, DeviceRules(idle_s=0.3), prefix=prefix)
    client = redis.Redis.from_url(redis_url)
    assert devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM).message.endswith("(1 waiting)")
    assert 0 < client.pttl(devices.key("p")) <= 300
    assert devices.locate("p", dark_frame(FrameKind.id, 0.01), ROOM).message.endswith("(2 waiting)")
    time.sleep(0.5)
    assert client.exists(devices.key("p")) == 0
    assert devices.locate("p", dark_frame(FrameKind.id, 0.02), ROOM).message.endswith("(1 waiting)")


def test_an_unreadable_record_is_started_afresh(redis_url, prefix, caplog):
    devices = SharedDevices.from_url(redis_url, prefix=prefix)
    redis.Redis.from_url(redis_url).set(devices.key("p"), json.dumps({"format": -1}))
    assert devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM).message.endswith("(1 waiting)")
    assert "device 'p' starts afresh: a device record of format -1" in caplog.text


def test_a_record_over_the_bound_is_refused_by_name_and_not_stored(redis_url, prefix, monkeypatch):
    devices = SharedDevices.from_url(redis_url, prefix=prefix)
    devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM)
    before = redis.Redis.from_url(redis_url).get(devices.key("p"))
    monkeypatch.setattr(shared, "MAX_RECORD_BYTES", len(before))  # the next ID frame makes it grow
    with pytest.raises(SessionStoreError) as refused:
        devices.locate("p", dark_frame(FrameKind.id, 0.01), ROOM)
    assert refused.value.code == "session_too_large" and "device 'p'" in refused.value.message
    assert redis.Redis.from_url(redis_url).get(devices.key("p")) == before


def test_redis_stopped_is_a_clear_error_within_seconds():
    with RedisServer() as server:
        devices = SharedDevices.from_url(server.url)
        devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM)
        assert devices.unavailable() is None
        server.stop()
        started = time.monotonic()
        with pytest.raises(SessionStoreError) as failed:
            devices.locate("p", dark_frame(FrameKind.id, 0.01), ROOM)
        assert time.monotonic() - started < 3.0
        assert failed.value.code == "redis_unavailable"
        assert failed.value.message.startswith(f"{describe(server.url)} did not answer: "), failed.value.message
        assert devices.unavailable().startswith(f"{describe(server.url)} does not answer: ")


def test_a_redis_that_never_answers_times_out_rather_than_hangs():
    with socket.socket() as silent:  # accepts connections (the kernel does), never replies
        silent.bind(("127.0.0.1", 0))
        silent.listen(8)
        url = f"redis://127.0.0.1:{silent.getsockname()[1]}/0"
        devices = SharedDevices.from_url(url)
        started = time.monotonic()
        with pytest.raises(SessionStoreError) as failed:
            devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM)
        took_s = time.monotonic() - started
    assert failed.value.code == "redis_unavailable" and "Timeout" in failed.value.message, failed.value.message
    assert took_s < 2 * (redis_store.CONNECT_TIMEOUT_S + redis_store.COMMAND_TIMEOUT_S) + 1, took_s


def test_the_password_is_not_named():
    assert describe("redis://user:secret@redis.local:6380/1") == "Redis at redis.local:6380/1"
    assert describe("redis://redis.local:6379/0") == "Redis at redis.local:6379/0"


def test_a_full_redis_refuses_by_name():
    """Redis at its maxmemory with nothing it may evict answers OOM: a clear error, not a 500."""
    with RedisServer() as server:
        redis.Redis.from_url(server.url).config_set("maxmemory", "1")  # every write is over the limit
        with pytest.raises(SessionStoreError) as refused:
            SharedDevices.from_url(server.url).locate("p", dark_frame(FrameKind.id, 0.0), ROOM)
    assert refused.value.code == "redis_unavailable"
    assert refused.value.message == (f"{describe(server.url)} refused the session: "
                                     "command not allowed when used memory > 'maxmemory'.")


def _slow_exec_proxy(redis_port: int, delay_s: float) -> int:
    """A TCP proxy to Redis that holds back the reply to the first EXEC for `delay_s` (past the client's
    timeout, while Redis has applied it): the port it listens on."""
    import asyncio

    armed, ports = {"exec": True, "hold": False}, []

    async def pump(reader, writer, to_server: bool) -> None:
        while data := await reader.read(65536):
            if to_server and b"EXEC" in data and armed["exec"]:
                armed["exec"], armed["hold"] = False, True
            if not to_server and armed["hold"]:
                armed["hold"] = False
                await asyncio.sleep(delay_s)
            try:
                writer.write(data)
                await writer.drain()
            except OSError:
                return
        writer.close()

    async def handle(client_reader, client_writer) -> None:
        server_reader, server_writer = await asyncio.open_connection("127.0.0.1", redis_port)
        await asyncio.gather(pump(client_reader, server_writer, True), pump(server_reader, client_writer, False),
                             return_exceptions=True)

    async def serve() -> None:
        server = await asyncio.start_server(handle, "127.0.0.1", 0)
        ports.append(server.sockets[0].getsockname()[1])
        async with server:
            await server.serve_forever()

    threading.Thread(target=lambda: asyncio.run(serve()), daemon=True).start()
    while not ports:
        time.sleep(0.01)
    return ports[0]


def test_a_lost_exec_reply_is_an_error_not_a_second_locate(redis_url):
    """redis-py raises WatchError when the connection fails while watching, though Redis may have applied
    EXEC: retrying located the frame twice (an ID frame's stripes kept twice, a pose frame tracked twice)."""
    port = _slow_exec_proxy(int(redis_url.rsplit(":", 1)[1].split("/")[0]), redis_store.COMMAND_TIMEOUT_S + 1)
    devices = SharedDevices.from_url(f"redis://127.0.0.1:{port}/0")
    with pytest.raises(SessionStoreError) as failed:
        devices.locate("p", dark_frame(FrameKind.id, 0.0), ROOM)
    assert failed.value.code == "redis_unavailable" and "did not confirm" in failed.value.message
    time.sleep(redis_store.COMMAND_TIMEOUT_S)  # the held reply has gone by
    _, waiting = load_device(redis.Redis.from_url(redis_url).get(devices.key("p")), ROOM, LocateOptions().session)
    assert len(waiting) == 1 and devices.conflicts == 0  # kept once, and not counted as another writer's change
