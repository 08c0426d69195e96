"""Rooms with several panels: crops, the choice and fusion of fixes, and the dispatcher's room path."""

import numpy as np

from server.locator import locate
from server.outcomes import Fix, Refusal
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from server.rooms import PanelFix, choose_and_fuse, locate_panel
from server.vision.beacons import find_beacon_blobs
from shared_schemas import BeaconIdSource, FailureReason
from tests.helpers import POSE, TWO_PANELS, WIDTH, two_panel_frame

MAP = TWO_PANELS


def test_every_panel_is_found_and_located_on_its_own_crop():
    frame = two_panel_frame()
    found = find_beacon_blobs(frame.pixels)
    assert len(found.blobs) == 2 and not any(b.cut_off for b in found.blobs)
    options = PipelineOptions(gravity_mode=GravityMode.never)
    for blob in found.blobs:
        # which blob is which: the one left in the image is beacon 17 (x grows to the right)
        beacon = MAP.beacons[0] if blob.centroid_px[0] < WIDTH / 2 else MAP.beacons[1]
        others = [b for b in found.blobs if b is not blob]
        fix = locate_panel(frame, blob, others, beacon, BeaconIdSource.vlc, options, found.levels.background)
        assert not isinstance(fix, Refusal), fix.message
        assert fix.beacon_id == beacon.id and fix.id_source is BeaconIdSource.vlc
        assert np.hypot(*(fix.position_m[:2] - POSE.position_m[:2])) < 0.004
        # pixels are reported in the full frame, on the blob
        assert np.hypot(*(fix.center_px - blob.centroid_px)) < 3.0
        assert np.all(np.abs(fix.corners_px.mean(axis=0) - blob.centroid_px) < 3.0)


def _fix(beacon_id, position, area):
    beacon = next(b for b in MAP.beacons if b.id == beacon_id)
    blob = find_beacon_blobs(two_panel_frame().pixels).blobs[0]
    blob = type(blob)(blob.contour_px, blob.bounding_box, blob.centroid_px, area, False)
    fix = Fix(position_m=np.array(position, float), rotation_wc=np.eye(3), beacon_id=beacon_id,
              id_source=BeaconIdSource.vlc, reprojection_error_px=0.1, gravity_used=False)
    return PanelFix(blob, beacon, fix)


def test_agreeing_fixes_are_fused_and_a_disagreeing_one_is_left_out_and_said():
    best = _fix(17, [0.0, 0.0, 0.0], 5000.0)
    close = _fix(42, [0.004, 0.0, 0.0], 4000.0)
    far = _fix(42, [1.2, 0.0, 0.0], 3000.0)
    fused = choose_and_fuse([best, close, far])
    assert fused.beacon.id == 17
    assert 0.0 < fused.fix.position_m[0] < 0.004
    assert any("left out" in w for w in fused.fix.warnings)
    assert any("fused" in w for w in fused.fix.warnings)
    assert choose_and_fuse([]) is None


def test_a_pose_frame_of_a_multi_beacon_map_is_refused_with_the_way_out():
    result = locate(two_panel_frame(), MAP)
    assert not result.ok and result.reason is FailureReason.unknown_beacon
    assert "ID frames" in result.message and result.beacons_in_view == 2


def test_a_short_exposure_frame_is_decoded_by_the_hook():
    # one short frame holds ~12 chips of each 21-chip message: the hook says what it read
    result = locate(two_panel_frame(level_dn=200.0, exposure_s=1 / 8000, seed=1), MAP)
    assert result.beacons_in_view == 2
    if result.ok:
        assert result.beacon_id_source is BeaconIdSource.vlc and result.vlc.confident
        assert result.beacon_id in (17, 42)
    else:
        assert result.vlc is not None and result.vlc.candidates == 256
        assert not (result.vlc.confident and result.vlc.beacon_id not in (17, 42))
