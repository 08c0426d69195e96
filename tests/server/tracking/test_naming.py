"""Naming panels: association across captures by relative position, VLC evidence, the track's hand-over."""

import numpy as np

from server.outcomes import Fix
from server.tracking.naming import NamingRules, PanelNamer
from server.tracking.track import Track
from server.vision.beacons import BeaconBlob
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconIdSource, BeaconMap
from tests.server.vlc.conftest import id_frames

ROOM = BeaconMap(
    name="room",
    beacons=[Beacon(id=17, center_m=[0.0, 0.0, 2.7], side_m=0.174), Beacon(id=42, center_m=[1.2, 0.0, 2.7], side_m=0.174)],
)
BLOB = BeaconBlob(np.zeros((4, 2)), (10, 10, 20, 20), (20.0, 20.0), 400.0, False)


def relative(x: float, y: float) -> Fix:
    """A fix relative to the template beacon at the origin: the camera 1.4 m below it."""
    return Fix(np.array([x, y, -1.4]), np.eye(3), None, None, 0.1, False)


def test_an_unnamed_panel_gives_no_fix_and_is_followed_across_captures():
    namer, track = PanelNamer(ROOM), Track()
    assert namer.name(BLOB, relative(0.1, 0.0), [], 0.0, track, namer.new_capture(0.0)) is None
    assert namer.name(BLOB, relative(0.15, 0.0), [], 0.5, track, namer.new_capture(0.5)) is None
    assert len(namer.panels) == 1  # moved 5 cm: the same panel
    assert namer.name(BLOB, relative(1.0, 0.0), [], 1.0, track, namer.new_capture(1.0)) is None
    assert len(namer.panels) == 2  # 85 cm away: another panel


def test_a_panel_unseen_longer_than_a_capture_is_not_continued_without_a_track():
    namer, track = PanelNamer(ROOM, NamingRules(unpredicted_timeout_s=0.6)), Track()
    namer.name(BLOB, relative(0.1, 0.0), [], 0.0, track, namer.new_capture(0.0))
    namer.panels[0].beacon_id = 17
    # after 0.8 s a walker at 1 m/s may stand under the next panel at the same relative position
    assert namer.name(BLOB, relative(0.1, 0.0), [], 0.8, track, namer.new_capture(0.8)) is None


def test_a_named_panel_keeps_its_name_and_places_the_fix_in_the_map():
    namer, track = PanelNamer(ROOM), Track()
    namer.name(BLOB, relative(0.1, 0.0), [], 0.0, track, namer.new_capture(0.0))
    namer.panels[0].beacon_id = 42  # decoded earlier
    named = namer.name(BLOB, relative(0.12, 0.01), [], 0.5, track, namer.new_capture(0.5))
    assert named is not None and named.beacon.id == 42
    assert named.fix.id_source is BeaconIdSource.vlc and named.fix.beacon_id == 42
    np.testing.assert_allclose(named.fix.position_m, [1.32, 0.01, 1.3])


def test_an_established_track_carries_the_id_of_the_beacon_it_predicts():
    namer, track = PanelNamer(ROOM), Track()
    for k in range(3):  # standing still under beacon 42: an established track at (1.3, 0, 1.3)
        track.add(0.5 * k, np.array([1.3, 0.0, 1.3]))
    named = namer.name(BLOB, relative(0.1, 0.0), [], 1.5, track, namer.new_capture(1.5))
    assert named is not None and named.beacon.id == 42 and named.fix.id_source is BeaconIdSource.track


def test_the_track_does_not_carry_an_id_when_two_beacons_are_about_as_likely():
    close = BeaconMap(name="close", beacons=[Beacon(id=17, center_m=[0.0, 0.0, 2.7], side_m=0.174),
                                             Beacon(id=42, center_m=[0.4, 0.0, 2.7], side_m=0.174)])
    namer, track = PanelNamer(close), Track()
    for k in range(3):  # between the two panels: 0.15 m from one hypothesis, 0.25 m from the other
        track.add(0.5 * k, np.array([0.2, 0.0, 1.3]))
    assert namer.name(BLOB, relative(0.05, 0.0), [], 1.5, track, namer.new_capture(1.5)) is None
    far_track = Track()
    for k in range(3):  # right under beacon 17's hypothesis: carried
        far_track.add(0.5 * k, np.array([0.05, 0.0, 1.3]))
    named = PanelNamer(close).name(BLOB, relative(0.05, 0.0), [], 1.5, far_track, set())
    assert named is not None and named.beacon.id == 17


def test_when_the_track_and_the_vlc_name_disagree_the_track_wins_and_the_evidence_is_dropped():
    namer, track = PanelNamer(ROOM), Track()
    for k in range(3):
        track.add(0.5 * k, np.array([1.3, 0.0, 1.3]))
    namer.name(BLOB, relative(0.1, 0.0), [], 1.4, track, namer.new_capture(1.4))
    namer.panels[0].beacon_id = 17  # a mis-association named it after the other panel
    named = namer.name(BLOB, relative(0.1, 0.0), [], 1.5, track, namer.new_capture(1.5))
    assert named is not None and named.beacon.id == 42 and named.fix.id_source is BeaconIdSource.track
    assert namer.stats.conflicts == 1 and namer.panels[0].beacon_id is None


def test_two_sightings_in_one_capture_never_continue_the_same_panel():
    namer, track = PanelNamer(ROOM), Track()
    claimed = namer.new_capture(0.0)
    namer.name(BLOB, relative(0.1, 0.0), [], 0.0, track, claimed)
    namer.name(BLOB, relative(0.12, 0.0), [], 0.0, track, claimed)
    assert len(namer.panels) == 2


def test_the_decoder_s_hypotheses_are_the_map_s_ids_and_stripes_outside_it_name_no_panel():
    namer, track = PanelNamer(ROOM), Track()
    assert namer.new_evidence().map_ids == (17, 42) and namer.new_evidence().hypotheses == 3
    # a panel coded 43, one bit from the map's 42, 1.4 m away: 8 ID frames of it in one capture
    stripes = [read_id_frame(f).panels[0].observation for f in id_frames(43, 1.4, 1 / 8000, 8, seed=5)]
    assert namer.name(BLOB, relative(0.1, 0.0), stripes, 5.3, track, namer.new_capture(5.3)) is None
    assert namer.stats.foreign_ids == 1 and namer.stats.vlc_ids == 0
    assert len(namer.notes) == 1 and "read as ID 43, not in map 'room'" in namer.notes[0]
    # surely none of the map's: the evidence starts afresh, and the next capture's notes are its own
    assert namer.panels[0].beacon_id is None and not namer.panels[0].evidence.observations
    namer.new_capture(5.8)
    assert namer.notes == []
