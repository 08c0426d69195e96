"""ID frames of LEDs at any modulation depth (issue 29): 0.3 (shallow stripes) to 1.0 (fully off
between chips, a comb of separate bars with dark rows between them, as real OOK/PWM drivers show)."""

import math

import numpy as np
import pytest

from server.ingest import LumaFrame
from server.rooms import read_room
from server.vision.beacons import CandidateRules, blob_mask, find_beacon_blobs
from server.vlc.capture import frame_blobs, stripe_gap_rows
from server.vlc.codec import longest_low_run_chips
from server.vlc.decoder import IdEvidence, row_time_s
from server.vlc.flatten import flatten_stripes
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconMap
from tests.server.vlc.conftest import CAMERA, HEIGHT, SKEW_S, WIDTH, id_frames

SQUARE_600 = {"side_m": 0.6, "corner_radius_m": 0.01}


@pytest.mark.parametrize("depth", [1.0, 0.6, 0.3])
def test_id_frames_at_any_depth_are_one_blob_each_and_read_right(depth):
    # a 0.174 m panel at 1.5 m (~8 chips a frame, yawed 20 degrees): at depth 1.0 two to three separate bars
    frames = id_frames(0x5A, 1.5, 1 / 8000, 6, seed=11, depth=depth)
    evidence = IdEvidence()
    decisions = []
    for frame in frames:
        reading = read_id_frame(frame)
        assert len(reading.panels) == 1, frame_blobs(frame).rejected
        (panel,) = reading.panels
        assert panel.observation is not None
        evidence.add(panel.observation)
        decisions.append(evidence.decide())
    confident = [d for d in decisions if d.confident]
    assert confident, decisions[-1].message
    assert all(d.beacon_id == 0x5A for d in confident)


def test_a_full_depth_frame_shows_dark_rows_that_the_blob_bridges():
    (frame,) = id_frames(0x5A, 1.0, 1 / 8000, 1, seed=12, depth=1.0)
    found = frame_blobs(frame)
    (blob,) = found.blobs
    x, y, w, h = blob.bounding_box
    rows = frame.pixels[y : y + h, x : x + w].max(axis=1)
    assert np.sum(rows < 20) > 20  # fully dark rows inside the panel: the LED off
    assert not find_beacon_blobs(frame.pixels).blobs  # unbridged, the comb of bars is refused
    _, _, mask = blob_mask(frame.pixels, blob, found)
    inside = np.flatnonzero(mask.any(axis=1))
    assert np.all(np.diff(inside) == 1)  # the full-resolution mask too: one run of rows, dark ones included


def test_the_bridged_dark_run_is_the_code_s_longest_low_run_plus_the_exposure():
    assert longest_low_run_chips() == 2  # the header's 0 0; BMC holds a level at most 2 chips
    (frame,) = id_frames(7, 1.0, 1 / 8000, 1, seed=1)
    row_time = row_time_s(SKEW_S, HEIGHT)
    assert stripe_gap_rows(frame) == math.ceil((2 / 2500 + 1 / 8000) / row_time)  # 40 rows at 23.2 us
    long = LumaFrame(frame.pixels, frame.meta.model_copy(update={"exposure_s": 0.01}), frame.camera)
    assert stripe_gap_rows(long) == 0  # no stripes to bridge in a frame that cannot carry them


def _two_panel_frame(gap_rows_wanted: float, seed: int):
    """An ID frame of two 0.174 m panels at 1.5 m, one above the other in the image, both LEDs at depth 1.0,
    their outlines `gap_rows_wanted` rows apart; returns the frame and the true gap in rows."""
    from server.vlc.codec import LedWaveform
    from shared_schemas import FrameKind
    from simulator.fixtures import fixture_meta
    from simulator.led import row_gains
    from simulator.render import CameraPose, Emitter, SensorModel, beacon_outline_px, render_emitters

    rng = np.random.default_rng(seed)
    pose = CameraPose(np.zeros(3), np.eye(3))
    upper = Beacon(id=17, center_m=[0.0, 0.0, 1.5], side_m=0.174, corner_radius_m=0.02)
    top = beacon_outline_px(upper, CAMERA, pose)
    metres_per_row = 1.5 / CAMERA.fy
    offset_m = 0.174 + gap_rows_wanted * metres_per_row
    lower = Beacon(id=42, center_m=[0.0, offset_m, 1.5], side_m=0.174, corner_radius_m=0.02)
    bottom = beacon_outline_px(lower, CAMERA, pose)
    if bottom[:, 1].min() < top[:, 1].min():
        top, bottom = bottom, top
    gap = bottom[:, 1].min() - top[:, 1].max()
    t_s, exposure_s = 3.0, 1 / 8000
    emitters = []
    for beacon, outline in (
        (upper, beacon_outline_px(upper, CAMERA, pose)),
        (lower, beacon_outline_px(lower, CAMERA, pose)),
    ):
        wave = LedWaveform.for_beacon(beacon.id, depth=1.0, phase_s=rng.uniform(0, 1))
        emitters.append(Emitter(outline, 200.0, row_gains(wave, HEIGHT, SKEW_S / (HEIGHT - 1), exposure_s, t_s)))
    sensor = SensorModel(background_dn=3.0, plateau_dn=200.0, psf_sigma_px=1.2, electrons_per_dn=4.0, read_noise_dn=2.0)
    pixels = render_emitters(emitters, WIDTH, HEIGHT, sensor, rng)
    meta = fixture_meta(CAMERA, WIDTH, HEIGHT, pose).model_copy(
        update={
            "exposure_s": exposure_s,
            "rolling_shutter_skew_s": SKEW_S,
            "timestamp_ns": int(t_s * 1e9),
            "frame_kind": FrameKind.id,
        }
    )
    return LumaFrame(pixels, meta, CAMERA), gap


def test_two_full_depth_panels_further_apart_than_the_dark_run_stay_two():
    frame, gap = _two_panel_frame(60.0, seed=3)
    assert stripe_gap_rows(frame) < gap < 80  # close together, but further apart than any dark run of the code
    found = frame_blobs(frame)
    assert len(found.blobs) == 2, found.rejected
    assert all(not b.cut_off for b in found.blobs)
    reading = read_id_frame(frame)
    assert len(reading.panels) == 2 and all(p.observation is not None for p in reading.panels)


def _flattened_600_mm_panel(seed: int):
    """A 600 mm panel at 1.5 m at depth 1.0, ID 0xA5: (frame, mask origin, mask, flattened pixels, problem)."""
    (frame,) = id_frames(0xA5, 1.5, 1 / 8000, 1, seed=seed, shape=SQUARE_600, depth=1.0)
    looks = CandidateRules().for_beacons([Beacon(id=0, center_m=[0, 0, 2], **SQUARE_600)])
    found = frame_blobs(frame, looks)
    (blob,) = found.blobs
    y0, x0, mask = blob_mask(frame.pixels, blob, found, looks, margin_px=10)
    meta = frame.meta
    pixels = np.array(frame.pixels)
    row_time = row_time_s(meta.rolling_shutter_skew_s, meta.height)
    problem = flatten_stripes(pixels, mask, (y0, x0), found.levels.background, 0xA5, row_time, meta.exposure_s)
    return frame, (y0, x0), mask, pixels, problem


def test_a_full_depth_panel_is_flattened_and_measured_its_dark_rows_from_their_neighbours():
    frame, (y0, x0), mask, pixels, problem = _flattened_600_mm_panel(seed=15)
    assert problem is None
    window = pixels[y0 : y0 + mask.shape[0], x0 : x0 + mask.shape[1]]
    inner = [window[r, mask[r]].mean() for r in range(10, mask.shape[0] - 10) if mask[r].sum() > 40]
    assert min(inner) > 0.6 * max(inner)  # no dark row is left inside the panel (they were at the background)
    # the room path names it by its stripes and measures it on the flattened frame (a corner in a dark
    # stripe is bridged by a chord: the pose stage's consistency test refuses such an outline, not here)
    beacon = Beacon(id=0xA5, center_m=[0.0, 0.0, 1.5], **SQUARE_600)
    far = Beacon(id=3, center_m=[30.0, 0.0, 1.5], **SQUARE_600)
    (panel,) = read_room(frame, BeaconMap(name="one", beacons=[beacon, far])).panels
    assert panel.beacon is not None and panel.beacon.id == 0xA5
    assert hasattr(panel.fix, "position_m"), panel.fix
    truth = np.array(frame.meta.ground_truth.position_m)
    assert np.linalg.norm(panel.fix.position_m[:2] - truth[:2]) < 0.005


def test_a_full_depth_panel_whose_end_lies_in_a_dark_stripe_is_not_flattened():
    frame, _, _, pixels, problem = _flattened_600_mm_panel(seed=7)
    assert problem is not None and "dark stripe" in problem and np.array_equal(pixels, frame.pixels)
