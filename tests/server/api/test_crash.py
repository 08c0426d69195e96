"""kill -9 of the server during bursts of map PUTs, sample POSTs and DELETEs, then a restart on
the same data folder: every stored item is whole or absent, nothing acknowledged is lost, no
leftover stays, no request fails with a 500 (docs/reliability.md, "Damaged data folder")."""

import random
import threading
import time
from pathlib import Path

import httpx

from shared_schemas import BeaconMap, FrameMeta, load_map
from simulator.local_server import LocalServer
from tests.conftest import API_KEY, FIXTURE

ROUNDS = 2
MAP_WRITERS, SAMPLE_WRITERS = 2, 2
HEADERS = {"X-API-Key": API_KEY}
FRAME = bytes(range(256))  # a 16 x 16 Y8 frame: no beacon, stored all the same, located in a millisecond
_BENCH = FrameMeta.model_validate_json(FIXTURE.read_bytes())
META = _BENCH.model_copy(
    update={"width": 16, "height": 16, "row_stride": 16, "ground_truth": None,
            "camera": _BENCH.camera.model_copy(update={"cx": 7.5, "cy": 7.5})}
)
FRAME_HEADERS = {**HEADERS, "Content-Type": "application/octet-stream", "X-Lumipose-Frame": META.model_dump_json()}


def _map(name: str, version: int) -> BeaconMap:
    """Version n of a map has n beacons, so the version on disk can be told after the crash."""
    beacon = load_map().beacons[0]
    return BeaconMap(
        name=name,
        beacons=[beacon.model_copy(update={"id": i, "center_m": [i * 0.5, 0.0, 1.0]}) for i in range(version)],
    )


class Writes:
    """What the writers sent and what the server acknowledged before it was killed."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.map_sent: dict[str, int] = {}  # name -> last version sent (one writer per name)
        self.map_acked: dict[str, int] = {}
        self.samples_acked: set[str] = set()
        self.samples_unanswered = 0  # POSTs cut by the kill: stored or not
        self.deleted: set[str] = set()  # acknowledged deletions
        self.delete_unanswered: set[str] = set()
        self.statuses: list[int] = []

    def put_maps(self, url: str, name: str, stop: threading.Event) -> None:
        with httpx.Client(base_url=url, headers=HEADERS, timeout=10) as http:
            while not stop.is_set() and self.map_sent.get(name, 0) < 255:
                version = self.map_sent.get(name, 0) + 1
                self.map_sent[name] = version
                try:
                    response = http.put(f"/v1/maps/{name}", content=_map(name, version).model_dump_json(by_alias=True),
                                        headers={"Content-Type": "application/json"})
                except httpx.TransportError:
                    return
                self.statuses.append(response.status_code)
                if response.status_code == 200:
                    self.map_acked[name] = version

    def post_samples(self, url: str, stop: threading.Event) -> None:
        with httpx.Client(base_url=url, headers=FRAME_HEADERS, timeout=10) as http:
            while not stop.is_set():
                try:
                    response = http.post("/v1/samples", content=FRAME)
                except httpx.TransportError:
                    with self.lock:
                        self.samples_unanswered += 1
                    return
                self.statuses.append(response.status_code)
                if response.status_code == 201:
                    with self.lock:
                        self.samples_acked.add(response.json()["id"])

    def delete_samples(self, url: str, stop: threading.Event) -> None:
        with httpx.Client(base_url=url, headers=HEADERS, timeout=10) as http:
            while not stop.is_set():
                with self.lock:
                    candidates = sorted(self.samples_acked - self.deleted - self.delete_unanswered)
                if not candidates:
                    time.sleep(0.005)
                    continue
                doomed = random.choice(candidates)
                try:
                    response = http.delete(f"/v1/samples/{doomed}")
                except httpx.TransportError:
                    self.delete_unanswered.add(doomed)
                    return
                self.statuses.append(response.status_code)
                if response.status_code == 204:
                    self.deleted.add(doomed)


def _check_after_restart(server: LocalServer, data_dir: Path, writes: Writes) -> None:
    health = httpx.get(f"{server.url}/healthz").json()
    assert health["status"] == "ok" and health["damaged"] == [], health
    hidden = [p.relative_to(data_dir).as_posix() for p in data_dir.rglob(".*") if p.name != ".write.lock"]
    assert hidden == [], f"leftovers after the restart: {hidden}"
    for name, sent in writes.map_sent.items():
        response = httpx.get(f"{server.url}/v1/maps/{name}")
        acked = writes.map_acked.get(name, 0)
        if acked == 0 and response.status_code == 404:
            continue  # the first version was cut before its rename
        assert response.status_code == 200, response.text
        assert len(response.json()["beacons"]) in (acked, sent), (name, acked, sent)  # the last answered or the cut one
    listed = {s["id"] for s in httpx.get(f"{server.url}/v1/samples").json()["samples"]}
    samples = data_dir / "samples"
    assert listed == ({p.name for p in samples.iterdir()} if samples.exists() else set())
    assert writes.samples_acked - writes.deleted - writes.delete_unanswered <= listed, "an acknowledged sample is lost"
    assert not listed & writes.deleted, "an acknowledged deletion came back"
    assert len(listed - writes.samples_acked) <= writes.samples_unanswered
    writes.samples_acked |= listed  # a sample stored by a POST the kill cut is acknowledged now
    for sample_id in listed:
        assert (samples / sample_id / "frame.bin").read_bytes() == FRAME
    for sample_id in sorted(listed)[:5]:
        response = httpx.get(f"{server.url}/v1/samples/{sample_id}/frame")
        assert response.status_code == 200 and response.content == FRAME
    evaluation = httpx.get(f"{server.url}/v1/samples/evaluation", timeout=60)
    assert evaluation.status_code == 200 and evaluation.json()["samples"] == len(listed), evaluation.text


def test_kill_9_during_bursts_of_writes_leaves_every_item_whole_or_absent(tmp_path):
    data_dir = tmp_path / "data"
    data_dir.mkdir()
    writes, logs, rng = Writes(), [], random.Random(5)
    for _ in range(ROUNDS):
        with LocalServer("--api-key", API_KEY, "--log-level", "warning", data_dir=data_dir) as server:
            logs.append(server.log_path)
            _check_after_restart(server, data_dir, writes)
            stop = threading.Event()
            threads = [threading.Thread(target=writes.put_maps, args=(server.url, f"crash-{i}", stop))
                       for i in range(MAP_WRITERS)]
            threads += [threading.Thread(target=writes.post_samples, args=(server.url, stop))
                        for _ in range(SAMPLE_WRITERS)]
            threads.append(threading.Thread(target=writes.delete_samples, args=(server.url, stop)))
            for thread in threads:
                thread.start()
            time.sleep(rng.uniform(0.3, 0.8))
            server.process.kill()  # SIGKILL: no shutdown, no finally
            server.process.wait()
            stop.set()
            for thread in threads:
                thread.join(timeout=30)
    with LocalServer("--api-key", API_KEY, "--log-level", "warning", data_dir=data_dir) as server:
        logs.append(server.log_path)
        _check_after_restart(server, data_dir, writes)
    assert len(writes.statuses) > 50 and set(writes.statuses) <= {200, 201, 204}, sorted(set(writes.statuses))
    for log in logs:
        assert "Traceback" not in log.read_text(), log.read_text()
