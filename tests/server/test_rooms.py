"""Rooms with several panels: crops, the choice and fusion of fixes, and the dispatcher's room path."""

import numpy as np
import pytest

from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.locator import locate
from server.outcomes import Fix, Refusal
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from server.rooms import PanelFix, choose_and_fuse, locate_panel, read_room, room_result
from server.vision.beacons import find_beacon_blobs
from server.vlc.codec import LedWaveform
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, FrameKind
from simulator.fixtures import fixture_meta
from simulator.led import row_gains
from simulator.render import CameraPose, Emitter, SensorModel, beacon_outline_px, render_emitters
from tests.helpers import CAMERA, HEIGHT, POSE, TWO_PANELS, WIDTH, two_panel_frame

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
        fix = locate_panel(frame, blob, others, beacon, BeaconIdSource.vlc, options, found.levels)
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
        assert result.vlc is not None and result.vlc.candidates == 3  # the map's 2 IDs and "none of them"
        assert not (result.vlc.confident and result.vlc.beacon_id not in (17, 42))


# Issue 11: panels cut by the frame border, named by the rows still in view. Two 600 x 600 mm
# panels 1.2 m above a quarter-resolution Mi 8 front camera (970 x 1296, 23.2 us per row): a
# whole panel spans ~570 rows, 32 chips; one frame holds a whole ID from 20 chips, 346 rows.
CUT_POSE = CameraPose(np.array([0.02, -0.03, 0.0]), rotation_from_ypr(10.0, 2.0, -1.0))


def big_panels(second_m, first_m=(-0.15, 0.0)) -> BeaconMap:
    return BeaconMap(name="big", beacons=[
        Beacon(id=17, center_m=[*first_m, 1.2], side_m=0.6, corner_radius_m=0.01),
        Beacon(id=42, center_m=[*second_m, 1.2], side_m=0.6, corner_radius_m=0.01),
    ])


def room_id_frame(beacon_map: BeaconMap, seed=0, t_s=0.0) -> LumaFrame:
    """One 1/8000 s ID frame of every panel of `beacon_map`, each with its own code and phase."""
    rng = np.random.default_rng(seed)
    exposure_s, row_time = 1 / 8000, 0.03 / (HEIGHT - 1)
    emitters = [
        Emitter(beacon_outline_px(b, CAMERA, CUT_POSE), 200.0,
                row_gains(LedWaveform.for_beacon(b.id, phase_s=0.001 * b.id), HEIGHT, row_time, exposure_s, t_s))
        for b in beacon_map.beacons
    ]
    sensor = SensorModel(background_dn=3.0, plateau_dn=200.0, psf_sigma_px=1.0, electrons_per_dn=4.0,
                         read_noise_dn=2.0)
    pixels = render_emitters(emitters, WIDTH, HEIGHT, sensor, rng)
    gravity = (CUT_POSE.rotation_wc.T @ [0, 0, -1.0]).tolist()
    meta = fixture_meta(CAMERA, WIDTH, HEIGHT, CUT_POSE, gravity_camera=gravity).model_copy(update={
        "exposure_s": exposure_s, "rolling_shutter_skew_s": 0.03, "timestamp_ns": int(t_s * 1e9),
        "frame_kind": FrameKind.id})
    return LumaFrame(pixels, meta, CAMERA)


def error_mm(fix) -> float:
    assert isinstance(fix, Fix), fix.message
    return 1000 * float(np.linalg.norm(fix.position_m - CUT_POSE.position_m))


@pytest.mark.parametrize("second_m, cut_rows", [
    ((0.7, 0.0), "all"),  # cut by the right border: every row of the panel is still in view
    ((0.0, 0.6), "most"),  # cut by the bottom border: ~440 of its ~570 rows in view, 25 chips
])
def test_a_panel_cut_by_the_border_is_named_by_its_visible_rows_and_located(second_m, cut_rows):
    beacon_map = big_panels(second_m, first_m=(-0.15, 0.0) if cut_rows == "all" else (0.0, -0.2))
    frame = room_id_frame(beacon_map)
    room = read_room(frame, beacon_map)
    assert room.problem is None and room.in_view == 2
    whole, cut = sorted(room.panels, key=lambda p: p.blob.cut_off)
    assert not whole.blob.cut_off and cut.blob.cut_off
    for panel, beacon_id in ((whole, 17), (cut, 42)):
        assert panel.beacon is not None and panel.beacon.id == beacon_id, panel.note
        assert panel.vlc.confident and panel.vlc.beacon_id == beacon_id and panel.vlc.candidates == 3
        assert panel.fix.id_source is BeaconIdSource.vlc and error_mm(panel.fix) < 5.0
    assert cut.vlc.chips_seen >= 20 and cut.note is None
    result = room_result(room, beacon_map)  # what locate() answers for this frame
    assert result.ok and result.beacon_id_source is BeaconIdSource.vlc and result.beacons_in_view == 2
    assert "position fused from beacons" in " ".join(result.warnings)
    assert np.linalg.norm(np.subtract(result.position_m, CUT_POSE.position_m)) < 0.005


def test_a_cut_panel_with_too_few_rows_in_view_is_not_named_and_the_result_says_why():
    beacon_map = big_panels((0.0, 0.95), first_m=(0.0, -0.2))  # 168 rows of the second panel in view
    frame = room_id_frame(beacon_map)
    room = read_room(frame, beacon_map)
    cut = next(p for p in room.panels if p.blob.cut_off)
    assert cut.beacon is None and cut.fix is None
    assert cut.vlc is not None and cut.vlc.chips_seen < 16
    assert "not named" in cut.note and "visible rows" in cut.note and "346 rows" in cut.note
    result = locate(frame, beacon_map)
    assert result.ok and result.beacon_id == 17  # the whole panel still gives the fix
    assert any("not named" in w and "16 chips" in w for w in result.warnings)
    # the cut panel alone: no fix, and the same reason
    alone = big_panels((0.0, 0.95), first_m=(0.0, -2.5))
    result = locate(room_id_frame(alone), alone)
    assert not result.ok and result.reason is FailureReason.unknown_beacon and result.beacons_in_view == 1
    assert any("not named" in w for w in result.warnings)
