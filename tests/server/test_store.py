"""The service's data folder: map precedence, re-reading replaced maps, atomic writes, damaged files,
crashes mid-write."""

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

import server.store as store_module
from server.store import LOCK_FILE, STALE_AFTER_S, MapStore, ProfileStore, SampleStore, StoreError, write_atomic
from shared_schemas import BeaconMap, FailureReason, FrameMeta, LocateResult, load_map
from shared_schemas.models import MeasuredPinhole
from tests.helpers import CALIBRATED, FRONT


def test_startup_map_is_the_default_and_stored_maps_override(tmp_path):
    office = load_map().model_copy(update={"name": "office"})
    startup = tmp_path / "office.json"
    startup.write_text(office.model_dump_json(by_alias=True))
    store = MapStore(tmp_path / "data", startup)
    assert store.default_name() == store.active_name() == "office"
    assert {s.name: s.source for s in store.summaries()} == {"test-bench": "bundled", "office": "startup"}
    moved = office.model_copy(update={"beacons": [office.beacons[0].model_copy(update={"center_m": [1, 2, 3]})]})
    store.put("office", moved)
    assert store.get("office") == moved and {s.source for s in store.summaries()} == {"bundled", "stored"}


def test_only_stored_maps_not_active_are_deleted(tmp_path):
    startup = tmp_path / "office.json"
    startup.write_text(load_map().model_copy(update={"name": "office"}).model_dump_json(by_alias=True))
    store = MapStore(tmp_path / "data", startup)
    store.put("room", _room(2))
    store.put("test-bench", _room(1).model_copy(update={"name": "test-bench"}))  # hides the bundled map
    refusals = {}
    for name in ("office", "missing", "../x"):
        with pytest.raises(StoreError) as refused:
            store.delete(name)
        refusals[name] = refused.value.code
    assert refusals == {"office": "active_map", "missing": "not_found", "../x": "bad_name"}
    store.set_active("room")
    with pytest.raises(StoreError) as refused:
        store.delete("room")
    assert refused.value.code == "active_map" and "activate another map" in refused.value.message
    store.set_active("test-bench")
    store.delete("room")
    store.set_active("office")
    store.delete("test-bench")  # the stored one: the bundled map of that name shows again
    with pytest.raises(StoreError) as refused:
        store.delete("test-bench")
    assert refused.value.code == "fixed_map" and "bundled map" in refused.value.message
    (tmp_path / "data" / "maps" / "hall.json").write_text("{damaged")
    store.delete("hall")
    assert {s.name: s.source for s in store.summaries()} == {"test-bench": "bundled", "office": "startup"}
    assert store.damaged() == []


def test_the_startup_map_stored_in_the_data_folder_is_not_deleted(tmp_path):
    # `serve --data-dir data --map room` starts from data/maps/room.json: deleting it would stop the next start
    MapStore(tmp_path).put("room", _room(2))
    store = MapStore(tmp_path, tmp_path / "maps" / "room.json")
    store.put("hall", _room(1).model_copy(update={"name": "hall"}))
    store.set_active("hall")
    with pytest.raises(StoreError) as refused:
        store.delete("room")
    assert refused.value.code == "fixed_map" and "started with" in refused.value.message
    assert (tmp_path / "maps" / "room.json").exists()


def test_many_threads_activating_and_deleting_never_lose_the_active_map(tmp_path):
    store = MapStore(tmp_path)
    names = [f"room{i}" for i in range(6)]
    maps = {name: _room(1).model_copy(update={"name": name}) for name in names}
    for name in names:
        store.put(name, maps[name])
    errors: list[BaseException] = []

    def churn(worker: int) -> None:
        for step in range(30):
            name = names[(worker + step) % len(names)]
            try:
                if (worker + step) % 2:
                    store.set_active(name)
                else:
                    store.delete(name)
                    store.put(name, maps[name])
            except StoreError as error:
                if error.code not in ("active_map", "not_found"):
                    errors.append(error)
            except BaseException as error:  # anything else is a bug
                errors.append(error)

    threads = [threading.Thread(target=churn, args=(worker,)) for worker in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert store.get(store.active_name()) is not None  # the active map is always there to locate in


def test_a_replaced_map_file_is_read_again(tmp_path):
    store = MapStore(tmp_path)
    first = load_map().model_copy(update={"name": "room"})
    store.put("room", first)
    assert store.get("room") == first
    second = first.model_copy(update={"beacons": [first.beacons[0].model_copy(update={"side_m": 0.6})]})
    store.put("room", second)  # same size on disk is possible: the cache keys on the file's identity too
    assert store.get("room").beacons[0].side_m == 0.6


def test_failed_write_leaves_the_old_file_whole_and_no_litter(tmp_path, monkeypatch):
    path = tmp_path / "map.json"
    write_atomic(path, b"old")

    def crash(*args):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", crash)
    with pytest.raises(OSError):
        write_atomic(path, b"new")
    assert path.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["map.json"]


def test_unknown_and_unsafe_names_are_refused(tmp_path):
    store, samples = MapStore(tmp_path), SampleStore(tmp_path)
    for name, code in (("nowhere", "not_found"), ("../etc/passwd", "bad_name")):
        with pytest.raises(StoreError) as refused:
            store.get(name)
        assert refused.value.code == code
    with pytest.raises(StoreError, match="no sample"):
        samples.get("../../x")


# --- Damaged files and interrupted writes (docs/reliability.md, "Damaged data folder") ---

FIXTURE_META = Path(__file__).parents[1] / "fixtures" / "bench_1m.json"
NO_FIX = LocateResult(ok=False, reason=FailureReason.no_beacon, message="none")


def _add(samples: SampleStore, frame: bytes = b"\x00" * 64) -> str:
    meta = FrameMeta.model_validate_json(FIXTURE_META.read_bytes())
    return samples.add(frame, meta, NO_FIX, label="1,2", device=None, map_name="test-bench").id


def _room(beacons: int) -> BeaconMap:
    beacon = load_map().beacons[0]
    return BeaconMap(
        name="room",
        beacons=[beacon.model_copy(update={"id": i, "center_m": [i * 0.5, 0.0, 1.0]}) for i in range(beacons)],
    )


def _hidden(data_dir: Path) -> list[str]:
    """What interrupted writes may leave: every hidden name in the data folder but the lock."""
    return sorted(p.relative_to(data_dir).as_posix() for p in data_dir.rglob(".*") if p.name != LOCK_FILE)


def test_damaged_maps_are_skipped_named_and_refused_and_a_put_repairs_them(tmp_path):
    maps = MapStore(tmp_path)
    maps.put("room", _room(2))
    maps.put("hall", _room(1).model_copy(update={"name": "hall"}))
    maps.set_active("room")
    (tmp_path / "maps" / "room.json").write_text('{"schema": "lumipose.map/1", "name": "ro')
    assert [s.name for s in maps.summaries()] == ["test-bench", "hall"]
    assert maps.damaged() == ["maps/room.json"]
    with pytest.raises(StoreError) as refused:
        maps.get("room")
    assert refused.value.code == "damaged_map" and "maps/room.json" in refused.value.message
    assert maps.active_name() == "room"  # named, so locates in it are refused, not moved to another map
    maps.put("room", _room(3))
    assert maps.get("room") == _room(3) and maps.damaged() == []


def test_a_damaged_active_map_file_means_the_default_map(tmp_path):
    maps = MapStore(tmp_path)
    maps.put("room", _room(1))
    maps.set_active("room")
    for damage in (b'{"na', b"\xff\xfe", b'{"name": "../x"}', b"[]"):
        (tmp_path / "active_map.json").write_bytes(damage)
        assert maps.active_name() == "test-bench" and maps.damaged() == ["active_map.json"]
    assert MapStore(tmp_path).damaged() == ["active_map.json"]  # found at start-up too
    maps.set_active("room")
    assert maps.active_name() == "room" and maps.damaged() == []


@pytest.mark.parametrize(
    "damage, named",
    [
        (lambda folder: (folder / "sample.json").write_text('{"id": "'), "sample.json"),
        (lambda folder: (folder / "sample.json").unlink(), "sample.json"),
        (lambda folder: (folder / "frame.bin").write_bytes(b"\x00" * 10), "frame.bin"),
        (lambda folder: (folder / "frame.bin").unlink(), "frame.bin"),
        (lambda folder: folder.rename(folder.with_name("0" * 32)), "sample.json"),  # a record of another id
    ],
)
def test_a_damaged_sample_is_skipped_named_refused_and_can_be_deleted(tmp_path, damage, named):
    samples = SampleStore(tmp_path)
    whole, broken = _add(samples), _add(samples)
    damage(tmp_path / "samples" / broken)
    broken = next(p.name for p in (tmp_path / "samples").iterdir() if p.name != whole)
    for store in (samples, SampleStore(tmp_path)):  # on read, and at start-up
        assert [s.id for s in store.all()] == [whole]
        assert store.damaged() == [f"samples/{broken}/{named}"]
        for read in (store.get, store.frame):
            with pytest.raises(StoreError) as refused:
                read(broken)
            assert refused.value.code == "damaged_sample" and f"samples/{broken}/{named}" in refused.value.message
    samples.delete(broken)
    assert not (tmp_path / "samples" / broken).exists() and samples.damaged() == [] and _hidden(tmp_path) == []
    assert samples.get(whole).id == whole


def test_unfinished_writes_are_never_listed_and_are_removed_at_start_up(tmp_path):
    """The ghost: a staging folder (a crash before its rename) has a sample.json; a half-deleted
    folder may still have one. Neither is listed; building a store removes them."""
    samples = SampleStore(tmp_path)
    kept = _add(samples)
    ghost = uuid.uuid4().hex
    shutil.copytree(tmp_path / "samples" / kept, tmp_path / "samples" / f".{ghost}.tmp")
    (tmp_path / "samples" / f".{ghost}.tmp" / "sample.json").write_text(
        (tmp_path / "samples" / kept / "sample.json").read_text().replace(kept, ghost)
    )
    shutil.copytree(tmp_path / "samples" / kept, tmp_path / "samples" / f".{kept}.{uuid.uuid4().hex}.deleted")
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / f".room.json.{uuid.uuid4().hex}.tmp").write_text('{"na')
    (tmp_path / f".active_map.json.{uuid.uuid4().hex}.tmp").write_text("")
    assert [s.id for s in samples.all()] == [kept] and len(_hidden(tmp_path)) == 4
    with pytest.raises(StoreError, match="no sample"):
        samples.get(ghost)
    MapStore(tmp_path), SampleStore(tmp_path)
    assert _hidden(tmp_path) == [] and [s.id for s in samples.all()] == [kept]


def test_the_clean_up_spares_what_a_live_writer_holds(tmp_path, monkeypatch):
    """Replicas share the folder: a writer in another process holds the lock shared while its
    temporary names exist, so a replica starting then removes only leftovers old enough to be
    surely dead."""
    monkeypatch.setattr(store_module, "LOCK_WAIT_S", 0.05)
    young, old = (tmp_path / "samples" / f".{uuid.uuid4().hex}.tmp" for _ in range(2))
    young.mkdir(parents=True), old.mkdir()
    os.utime(old, (time.time() - 2 * STALE_AFTER_S,) * 2)
    with store_module._data_lock(tmp_path, exclusive=False):
        SampleStore(tmp_path)
        assert young.exists() and not old.exists()
    SampleStore(tmp_path)
    assert not young.exists()


# --- Device profiles: stored beside the bundled ones, which are never replaced ---


def _calibrated(version: int):
    """CALIBRATED with its focal length changed by `version` px (the same size on disk)."""
    measured = CALIBRATED.intrinsics
    return CALIBRATED.model_copy(update={"intrinsics": measured.model_copy(update={"fx": measured.fx + version})})


def test_profiles_are_stored_listed_found_and_deleted_beside_the_bundled_ones(tmp_path):
    profiles = ProfileStore(tmp_path)
    bundled = {"xiaomi-mi8-front": "bundled", "xiaomi-mi8-rear": "bundled"}
    assert {s.id: s.source for s in profiles.summaries()} == bundled
    assert profiles.put(CALIBRATED.id, CALIBRATED) == CALIBRATED
    assert ProfileStore(tmp_path).get(CALIBRATED.id) == CALIBRATED  # on disk, for a restart or a replica
    summary = {s.id: s for s in profiles.summaries()}[CALIBRATED.id]
    assert summary.source == "stored" and summary.calibrated and (summary.width, summary.height) == (3880, 5184)
    assert set(profiles.table()) == {"xiaomi-mi8-front", "xiaomi-mi8-rear", CALIBRATED.id}
    profiles.put(CALIBRATED.id, _calibrated(1))
    assert profiles.get(CALIBRATED.id) == _calibrated(1)  # replaced, read again
    profiles.delete(CALIBRATED.id)
    with pytest.raises(StoreError, match="no device profile 'mi8-front-calibrated'; known: xiaomi-mi8-front, xia"):
        profiles.get(CALIBRATED.id)
    with pytest.raises(StoreError) as refused:
        profiles.delete(CALIBRATED.id)
    assert refused.value.code == "not_found" and _hidden(tmp_path) == []


@pytest.mark.parametrize(
    "call, code, field",
    [
        (lambda store: store.put("xiaomi-mi8-front", FRONT), "bundled_profile", "id"),
        (lambda store: store.delete("xiaomi-mi8-front"), "bundled_profile", "profile_id"),
        (lambda store: store.put("other", CALIBRATED), "name_mismatch", "id"),
        (lambda store: store.put("../x", CALIBRATED), "bad_name", "profile_id"),
        (lambda store: store.get("a b"), "bad_name", "profile_id"),
        (lambda store: store.put(CALIBRATED.id, CALIBRATED.model_copy(update={"intrinsics": MeasuredPinhole(
            fx=4000, fy=4000, cx=3880.5, cy=2000)})), "invalid_request", "intrinsics.cx"),
        (lambda store: store.put(CALIBRATED.id, CALIBRATED.model_copy(update={"intrinsics": MeasuredPinhole(
            fx=4000, fy=4000, cx=2000, cy=-1)})), "invalid_request", "intrinsics.cy"),
    ],
)
def test_bad_profile_writes_are_refused_and_leave_nothing(tmp_path, call, code, field):
    profiles = ProfileStore(tmp_path)
    with pytest.raises(StoreError) as refused:
        call(profiles)
    assert (refused.value.code, refused.value.field) == (code, field), refused.value.message
    assert not (tmp_path / "profiles").exists() or list((tmp_path / "profiles").iterdir()) == []
    assert profiles.get("xiaomi-mi8-front") == FRONT


def test_damaged_profiles_are_skipped_named_refused_and_can_be_deleted(tmp_path):
    profiles = ProfileStore(tmp_path)
    for version, name in enumerate(("cut", "moved", "kept")):
        profiles.put(name, _calibrated(version).model_copy(update={"id": name}))
    folder = tmp_path / "profiles"
    (folder / "cut.json").write_bytes((folder / "cut.json").read_bytes()[:50])
    (folder / "moved.json").rename(folder / "elsewhere.json")  # holds the profile 'moved'
    by_hand = CALIBRATED.model_copy(update={"id": "xiaomi-mi8-front"})
    (folder / "xiaomi-mi8-front.json").write_text(by_hand.model_dump_json())
    (folder / f".kept.json.{uuid.uuid4().hex}.tmp").write_text('{"i')  # an interrupted write
    damaged = ["profiles/cut.json", "profiles/elsewhere.json", "profiles/xiaomi-mi8-front.json"]
    for store in (profiles, ProfileStore(tmp_path)):  # on read, and at start-up
        assert _hidden(tmp_path) == []
        assert [s.id for s in store.summaries()] == ["xiaomi-mi8-front", "xiaomi-mi8-rear", "kept"]
        assert store.damaged() == damaged
        assert store.get("xiaomi-mi8-front") == FRONT  # the bundled one, never the file
        for name in ("cut", "elsewhere"):
            with pytest.raises(StoreError) as refused:
                store.get(name)
            assert refused.value.code == "damaged_profile" and f"profiles/{name}.json" in refused.value.message
        with pytest.raises(StoreError) as refused:
            store.table(named="cut")  # a frame naming it: refused by name, not as unknown
        assert refused.value.code == "damaged_profile" and refused.value.field == "profile_id"
        assert set(store.table(named="kept")) == {"xiaomi-mi8-front", "xiaomi-mi8-rear", "kept"}
    profiles.delete("cut")
    profiles.put("elsewhere", CALIBRATED.model_copy(update={"id": "elsewhere"}))
    assert profiles.damaged() == ["profiles/xiaomi-mi8-front.json"]


CRASHING_CHILD = """
import os, signal, sys
from pathlib import Path
from server.store import MapStore, ProfileStore, SampleStore
from tests.helpers import CALIBRATED
from tests.server.test_store import _add, _calibrated, _room

data_dir, operation, function, nth = Path(sys.argv[1]), sys.argv[2], sys.argv[3], int(sys.argv[4])
maps, samples, profiles = MapStore(data_dir), SampleStore(data_dir), ProfileStore(data_dir)
real, calls = getattr(os, function), [0]

def crash(*args, **kwargs):  # the process dies here, as under kill -9 or a power cut
    calls[0] += 1
    if calls[0] == nth:
        os.kill(os.getpid(), signal.SIGKILL)
    return real(*args, **kwargs)

setattr(os, function, crash)
if operation == "add":
    _add(samples, b"\\x01" * 64)
elif operation == "delete":
    samples.delete(sys.argv[5])
elif operation == "put":
    maps.put("room", _room(2))
elif operation == "put_profile":
    profiles.put(CALIBRATED.id, _calibrated(2))
else:
    maps.set_active("room")
"""


@pytest.mark.parametrize(
    "operation, function, nth, done",
    [
        ("add", "fsync", 1, False),  # frame.bin written in the staging folder
        ("add", "fsync", 3, False),  # the whole sample written, not yet moved into place
        ("add", "replace", 1, False),  # at the move: the ghost of the old code
        ("add", "fsync", 4, True),  # moved into place, before its folder is synced
        ("delete", "replace", 1, False),
        ("delete", "unlink", 1, True),  # moved aside, its removal cut short
        ("delete", "unlink", 3, True),
        ("put", "fsync", 1, False),  # the temporary file written
        ("put", "replace", 1, False),
        ("put", "fsync", 2, True),
        ("put_profile", "replace", 1, False),
        ("put_profile", "fsync", 2, True),
        ("activate", "replace", 1, False),
    ],
)
def test_a_crash_at_any_step_of_a_write_leaves_the_item_whole_or_absent(tmp_path, operation, function, nth, done):
    maps, samples = MapStore(tmp_path), SampleStore(tmp_path)
    maps.put("room", _room(1))
    ProfileStore(tmp_path).put(CALIBRATED.id, _calibrated(1))
    first = _add(samples)
    child = subprocess.run(
        [sys.executable, "-c", CRASHING_CHILD, str(tmp_path), operation, function, str(nth), first],
        cwd=Path(__file__).parents[2],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert child.returncode == -signal.SIGKILL, child.stderr

    maps, samples, profiles = MapStore(tmp_path), SampleStore(tmp_path), ProfileStore(tmp_path)  # the restart
    assert _hidden(tmp_path) == [] and maps.damaged() == [] and samples.damaged() == [] and profiles.damaged() == []
    assert profiles.get(CALIBRATED.id) == _calibrated(2 if operation == "put_profile" and done else 1)
    listed = [s.id for s in samples.all()]
    assert sorted(listed) == sorted(p.name for p in (tmp_path / "samples").iterdir())
    for sample_id in listed:
        assert samples.get(sample_id).frame_bytes == len(samples.frame(sample_id)) == 64
    if operation == "add":
        assert len(listed) == (2 if done else 1)
    if operation == "delete":
        assert listed == ([] if done else [first])
    assert maps.get("room") == _room(2 if operation == "put" and done else 1)
    assert maps.active_name() == "test-bench"
