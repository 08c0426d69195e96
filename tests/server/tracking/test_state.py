"""A device's record as plain data (server/tracking/state.py): a walk stored and read back after every
frame gives the same answers as one kept in memory, so any replica can take a device's next frame."""

import json

import numpy as np
import pytest

from server.options import LocateOptions
from server.tracking.devices import DeviceRecord, DeviceRules, locate_in_record
from server.tracking.state import STATE_FORMAT, StateError, dump_device, load_device, map_digest
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures
from tests.helpers import answer_without_timings, walk_frames, OTHER_ROOM, ROOM

OPTIONS, RULES = LocateOptions(), DeviceRules()


@pytest.fixture(scope="module")
def walk():
    config = OfficeConfig(walk="zigzag", max_captures=6, pose_scale=0.25, seed=3)
    pose_scene, _ = office_scenes(config)
    return pose_scene.beacon_map(), list(walk_captures(config))


def test_a_walk_stored_after_every_frame_answers_as_one_kept_in_memory(walk):
    beacon_map, captures = walk
    kept, stored = DeviceRecord(), DeviceRecord()
    sizes, fixes = [], 0
    for frame in walk_frames(captures):
        expected = locate_in_record(kept, frame, beacon_map, OPTIONS, RULES)
        got = locate_in_record(stored, frame, beacon_map, OPTIONS, RULES)
        assert answer_without_timings(got) == answer_without_timings(expected)
        fixes += got.ok
        data = dump_device(stored.session, stored.waiting)
        sizes.append(len(data))
        stored = DeviceRecord(*load_device(data, beacon_map, OPTIONS.session))
    assert fixes >= 4 and kept.session.track.fixes == stored.session.track.fixes
    assert max(sizes) < 512 * 1024, max(sizes)  # a record is kilobytes, not a frame


def test_waiting_stripes_survive_and_a_record_of_another_map_starts_a_new_session(walk):
    beacon_map, captures = walk
    record = DeviceRecord()
    for frame in [*captures[0].id_frames, captures[0].pose_frame, *captures[1].id_frames]:
        locate_in_record(record, frame, beacon_map, OPTIONS, RULES)
    assert record.session is not None and len(record.waiting) == len(captures[1].id_frames)
    session, waiting = load_device(dump_device(record.session, record.waiting), beacon_map, OPTIONS.session)
    for before, after in zip(record.waiting, waiting, strict=True):
        for a, b in zip(before.sightings, after.sightings, strict=True):
            assert a.centroid_norm == b.centroid_norm
            assert np.array_equal(a.observation.values_dn, b.observation.values_dn)
            assert np.array_equal(a.observation.row_offsets_s, b.observation.row_offsets_s)
    other, still_waiting = load_device(dump_device(record.session, record.waiting), ROOM, OPTIONS.session)
    assert other is None and len(still_waiting) == len(waiting)


def test_an_unreadable_record_is_refused_by_name_not_misread():
    good = dump_device(None, [])
    assert load_device(good, ROOM, OPTIONS.session)[0] is None
    for bad in (b"not json", b"[]", json.dumps({"format": STATE_FORMAT + 1}).encode(),
                json.dumps({"format": STATE_FORMAT, "waiting": [{"t_s": 1.0}], "session": None}).encode(),
                json.dumps({"format": STATE_FORMAT, "waiting": [], "session": {"map": map_digest(OTHER_ROOM)}}).encode()):
        with pytest.raises(StateError):
            load_device(bad, OTHER_ROOM, OPTIONS.session)
