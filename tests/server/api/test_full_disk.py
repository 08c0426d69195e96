"""A data folder with no room (docs/reliability.md, "Second hardening pass"): every map, profile, sample and
activation write answers 507 `insufficient_storage` naming the folder, what the folder held stays whole and
served, `/healthz` is degraded until a write succeeds again.

Two real conditions, against a real `lumipose serve`:
- ENOSPC: the data folder is a small tmpfs, filled up. Mounting needs root and a kernel that lets this
  process mount (not in most containers): skipped elsewhere, saying why.
- EFBIG: the server's RLIMIT_FSIZE lowered with prlimit, so a sample's frame cannot be written; runs
  wherever the server runs (Linux). EDQUOT (a quota) goes the same way in `server.store.FolderRoom` and is
  not made here.
"""

from __future__ import annotations

import errno
import os
import resource
import subprocess
import time
from pathlib import Path

import httpx
import pytest

from lumipose_client import Client, LumiposeError
from shared_schemas import BeaconMap, FrameMeta, device_profiles, load_map
from simulator.local_server import LocalServer

API_KEY = "disk-key"
FIXTURE = Path(__file__).parents[2] / "fixtures" / "bench_1m.json"
_BENCH = FrameMeta.model_validate_json(FIXTURE.read_bytes())


def _meta(width: int, height: int) -> FrameMeta:
    camera = _BENCH.camera.model_copy(update={"cx": (width - 1) / 2, "cy": (height - 1) / 2})
    return _BENCH.model_copy(update={"width": width, "height": height, "row_stride": width, "ground_truth": None,
                                     "camera": camera})


def _map(name: str, beacons: int) -> BeaconMap:
    beacon = load_map().beacons[0]
    return BeaconMap(name=name, beacons=[beacon.model_copy(update={"id": i, "center_m": [i * 0.5, 0.0, 1.0]})
                                         for i in range(beacons)])


def _mount_tmpfs(folder: Path) -> str | None:
    """None when `folder` is now a 4 MB tmpfs, else why it cannot be."""
    if os.geteuid() != 0:
        return "mounting a tmpfs needs root"
    run = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(folder)], capture_output=True,
                         text=True)
    return None if run.returncode == 0 else f"mount -t tmpfs failed: {run.stderr.strip() or run.returncode}"


@pytest.fixture(scope="module")
def disk(tmp_path_factory):
    """A server whose data folder is a 4 MB tmpfs when this process may mount one (else a plain folder), and
    whether it is."""
    folder = tmp_path_factory.mktemp("disk") / "data"
    folder.mkdir()
    why_not = _mount_tmpfs(folder)
    try:
        with LocalServer("--api-key", API_KEY, "--log-level", "warning", data_dir=folder) as server:
            yield server, why_not
        assert "Traceback" not in server.log(), server.log()
    finally:
        if why_not is None:
            subprocess.run(["umount", str(folder)], check=True)


def _fill(folder: Path) -> Path:
    filler = folder / "filler.bin"
    with open(filler, "wb") as handle:
        try:
            while True:
                handle.write(b"\0" * (64 << 10))
                handle.flush()
        except OSError as error:
            assert error.errno == errno.ENOSPC, error
    return filler


def _no_room(call, folder: Path, why: str) -> float:
    start = time.perf_counter()
    with pytest.raises(LumiposeError) as refused:
        call()
    seconds = time.perf_counter() - start
    assert refused.value.status == 507 and refused.value.body.error == "insufficient_storage", refused.value
    assert refused.value.body.field is None
    message = refused.value.body.message
    assert f"the data folder {folder} has no room ({why})" in message and "unchanged" in message, message
    return seconds


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob(".*") if p.name != ".write.lock")


def _while_full(client: Client, folder: Path, profile, sample_id: str, frame: bytes) -> None:
    full = os.strerror(errno.ENOSPC)
    seconds = [
        _no_room(lambda: client.put_map(_map("hall", 5)), folder, full),
        _no_room(lambda: client.put_map(_map("atrium", 3)), folder, full),
        _no_room(lambda: client.put_profile(profile.model_copy(update={"name": "renamed"})), folder, full),
        _no_room(lambda: client.store_sample(bytes(64 << 10), _meta(256, 256), compress=None), folder, full),
        _no_room(lambda: client.set_active_map("lobby"), folder, full),
    ]
    assert max(seconds) < 2.0, seconds
    # what the folder held is whole, and served
    assert len(client.get_map("hall").beacons) == 2
    assert "atrium" not in {m.name for m in client.maps()}
    assert client.profile("lab-phone").name == profile.name
    assert [s.id for s in client.samples().samples] == [sample_id]
    assert client.sample_frame(sample_id)[1] == frame
    assert client.active_map().name != "lobby"
    assert _leftovers(folder) == []  # no temporary file or staging folder left behind
    health = client.health()
    assert health.status == "degraded" and health.damaged == []
    assert any(line.startswith(f"data folder {folder}: no room to write") for line in health.unavailable), health


def test_a_full_disk_is_a_507_and_the_old_data_stays_whole(disk):
    server, why_not = disk
    if why_not is not None:
        pytest.skip(f"no full file system to test ENOSPC on: {why_not}")
    folder = server.data_dir
    profile = device_profiles()["xiaomi-mi8-rear"].model_copy(update={"id": "lab-phone"})
    frame = bytes(range(256))
    with Client(server.url, api_key=API_KEY) as client:
        client.put_map(_map("hall", 2))
        client.put_map(_map("lobby", 1))
        client.put_profile(profile)
        sample = client.store_sample(frame, _meta(16, 16), label="before", compress=None)
        filler = _fill(folder)
        try:
            _while_full(client, folder, profile, sample.id, frame)
        finally:
            filler.unlink()
        client.put_map(_map("hall", 5))
        client.put_profile(profile.model_copy(update={"name": "renamed"}))
        client.store_sample(frame, _meta(16, 16), compress=None)
        client.set_active_map("lobby")
        assert client.health().status == "ok" and client.health().unavailable == []
        assert len(client.get_map("hall").beacons) == 5
    assert "no room to write" in server.log() and "writes succeed again" in server.log()


def test_a_file_size_limit_is_a_507_too(disk):
    server, _ = disk
    limit = 1 << 20
    frame = bytes(1536 * 1024)  # 1.5 MB: frame.bin passes the limit
    meta = _meta(1536, 1024)
    _, hard = resource.prlimit(server.pid, resource.RLIMIT_FSIZE)
    with Client(server.url, api_key=API_KEY) as client:
        before = [s.id for s in client.samples().samples]
        resource.prlimit(server.pid, resource.RLIMIT_FSIZE, (limit, hard))
        try:
            seconds = _no_room(lambda: client.store_sample(frame, meta, compress=None), server.data_dir,
                               os.strerror(errno.EFBIG))
            assert seconds < 2.0
            assert [s.id for s in client.samples().samples] == before and _leftovers(server.data_dir) == []
            health = httpx.get(f"{server.url}/healthz", timeout=5).json()
            assert health["status"] == "degraded", health
            assert any(line.endswith(f"no room to write sample of {len(frame)} frame bytes (File too large)")
                       for line in health["unavailable"]), health
        finally:
            resource.prlimit(server.pid, resource.RLIMIT_FSIZE, (hard, hard))
        client.store_sample(frame, meta, compress=None)
        assert client.health().status == "ok"
