"""The service's data folder: map precedence, re-reading replaced maps, atomic writes."""

import os

import pytest

from server.store import MapStore, SampleStore, StoreError, write_atomic
from shared_schemas import load_map


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
