"""The survey's stages: the fit on exact geometry, its refusals, and rendered quarter-scale office frames."""

from __future__ import annotations

import gc
import math
import weakref
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.sparse import csr_matrix

from server.geometry import (
    beacon_corners_m,
    beacon_rotation,
    grown_quads,
    rotation_from_ypr,
    rotation_z,
    world_to_camera,
)
from server.survey.adjust import Adjusted, adjust, without_cameras_covariance
from server.survey.bearing import map_bearing
from server.survey.chain import chain_start, nearest_equivalent_deg
from server.survey.rules import SurveyInputError, SurveyRefused, SurveyRules
from server.survey.run import _without_outliers, survey
from server.survey.sightings import FrameSightings, Sighting, frame_sightings
from shared_schemas import Beacon, BeaconMap
from simulator.render import SensorModel, render_emitters
from shared_schemas.survey import PanelLabel, SkippedFrame
from tests.helpers import survey_frame, survey_set

MATRIX = np.array([[980.0, 0.0, 484.5], [0.0, 980.0, 647.5], [0.0, 0.0, 1.0]])
ROOM = BeaconMap(
    name="room",
    beacons=[
        Beacon(id=1, center_m=[0.0, 0.0, 2.7], side_m=0.2, corner_radius_m=0.02),
        Beacon(id=2, center_m=[1.2, 0.03, 2.71], yaw_deg=1.5, side_m=0.2, corner_radius_m=0.02),
        Beacon(id=3, center_m=[1.25, 1.2, 2.69], yaw_deg=-2.0, side_m=0.2, corner_radius_m=0.02),
    ],
)
GROWTH_PX = 1.5


def _sighting(
    beacon: Beacon, position: np.ndarray, rotation_wc: np.ndarray, rng, noise_px: float, growth_px: float = GROWTH_PX
) -> Sighting:
    """A whole panel seen from a camera: mid-level corners (grown by GROWTH_PX) and centre with noise, and a
    start pose a little off (as a single panel's fix would give)."""
    model = np.vstack([beacon_corners_m(beacon) @ beacon_rotation(beacon).T + beacon.center_m, beacon.center_m])
    pixels = world_to_camera(model, position, rotation_wc) @ MATRIX.T
    pixels = pixels[:, :2] / pixels[:, 2:]
    pixels[:4] = grown_quads(pixels[:4], growth_px)
    pixels += rng.normal(0.0, noise_px, pixels.shape)
    rotation_wb = beacon_rotation(beacon)
    off = rotation_from_ypr(*rng.normal(0.0, 0.3, 3))
    return Sighting(
        beacon=beacon,
        points_px=pixels,
        sigmas_px=np.array([0.05, 0.05, 0.05, 0.05, 0.03]),
        cut=False,
        grown=True,
        position_b=rotation_wb.T @ (position - beacon.center_m) + rng.normal(0.0, 0.01, 3),
        rotation_bc=rotation_wb.T @ off @ rotation_wc,
        area_px=1e4,
        growth_px=growth_px + 0.2,
    )


def _frames(
    pairs: list[tuple[int, ...]],
    rng,
    noise_px: float = 0.03,
    room: BeaconMap = ROOM,
    growths_px: dict[int, float] | None = None,
) -> list[FrameSightings]:
    """A frame under each group of panels (IDs), looking up at their middle with a little tilt; `growths_px`:
    each panel's clipped-edge growth (default GROWTH_PX for all)."""
    frames = []
    for k, ids in enumerate(pairs):
        beacons = [room.beacon(i) for i in ids]
        middle = np.mean([b.center_m for b in beacons], axis=0)
        position = middle + [*rng.normal(0.0, 0.2, 2), -1.3]
        rotation = rotation_from_ypr(rng.uniform(-180, 180), *rng.normal(0.0, 8.0, 2))
        gravity = rotation.T @ rotation_from_ypr(0.0, *rng.normal(0.0, 0.05, 2)) @ [0.0, 0.0, -1.0]
        frames.append(
            FrameSightings(
                name=f"f{k}",
                matrix=MATRIX,
                gravity_camera=gravity,
                gravity_sigma_deg=0.05,
                compass_bearing_deg=None,
                sightings=tuple(
                    _sighting(b, position, rotation, rng, noise_px, (growths_px or {}).get(b.id, GROWTH_PX))
                    for b in beacons
                ),
                notes=(),
            )
        )
    return frames


def _sketch(room: BeaconMap, anchor: int, error_m: float = 0.05, yaw_error_deg: float = 4.0) -> BeaconMap:
    rng = np.random.default_rng(7)
    moved = [
        b
        if b.id == anchor
        else b.model_copy(
            update={
                "center_m": list(np.asarray(b.center_m) + rng.normal(0.0, error_m, 3)),
                "yaw_deg": b.yaw_deg + rng.normal(0.0, yaw_error_deg),
            }
        )
        for b in room.beacons
    ]
    return room.model_copy(update={"beacons": moved})


def test_the_fit_finds_every_panel_from_a_rough_sketch_within_its_sigmas():
    rng = np.random.default_rng(1)
    frames = _frames([(1, 2), (2, 3), (1, 3), (1, 2, 3)] * 4, rng)
    adjusted = adjust(frames, chain_start(frames, _sketch(ROOM, 1), 1), 1, SurveyRules())
    for beacon in ROOM.beacons[1:]:
        estimate = adjusted.panels[beacon.id]
        error = estimate.pose.center_m - beacon.center_m
        assert np.linalg.norm(error) < 0.5e-3, (beacon.id, error)
        assert np.all(np.abs(error) < 5 * estimate.center_sigma_m + 2e-5), (error, estimate.center_sigma_m)
        assert abs(estimate.pose.yaw_deg - beacon.yaw_deg) < max(5 * estimate.yaw_sigma_deg, 0.005)
        assert 0 < estimate.center_sigma_m.max() < 1e-3
    assert adjusted.panels[1].pose.yaw_deg == 0.0 and np.all(adjusted.panels[1].center_sigma_m == 0)
    assert adjusted.rms_px < 0.1


def test_the_panels_covariance_is_the_whole_inverses_part_without_forming_it():
    """The Schur complement over the cameras' blocks gives the same panel (and growth) covariance as the dense
    inverse of the whole J^T J, on a random Jacobian of the fit's pattern."""
    rng = np.random.default_rng(4)
    panels, cameras = 3, 6
    jacobian = np.zeros((20 * cameras, 4 * panels + 6 * cameras + 2))
    for f in range(cameras):
        rows = slice(20 * f, 20 * f + 20)
        for p in rng.choice(panels, 2, replace=False):
            jacobian[rows, 4 * p : 4 * p + 4] = rng.normal(size=(20, 4))
        jacobian[rows, 4 * panels + 6 * f : 4 * panels + 6 * f + 6] = rng.normal(size=(20, 6))
        jacobian[rows, -2:] = rng.normal(size=(20, 2))
    whole = np.linalg.inv(jacobian.T @ jacobian)
    rest = [*range(4 * panels), jacobian.shape[1] - 2, jacobian.shape[1] - 1]
    reduced = without_cameras_covariance(csr_matrix(jacobian), 4 * panels, cameras)
    assert np.allclose(reduced, whole[np.ix_(rest, rest)], rtol=1e-8, atol=1e-12)


def test_panels_of_different_luminance_each_get_their_own_growth():
    """Panels 15 % brighter or dimmer grow by different amounts (here 1.2, 1.5, 1.8 px): one growth for all
    would shrink the bright ones and stretch the map; each panel's own is fitted."""
    rng = np.random.default_rng(8)
    frames = _frames([(1, 2), (2, 3), (1, 3), (1, 2, 3)] * 4, rng, growths_px={1: 1.5, 2: 1.8, 3: 1.2})
    adjusted = adjust(frames, chain_start(frames, _sketch(ROOM, 1), 1), 1, SurveyRules())
    for beacon in ROOM.beacons[1:]:
        error = adjusted.panels[beacon.id].pose.center_m - beacon.center_m
        assert np.linalg.norm(error) < 0.5e-3, (beacon.id, error)
    assert adjusted.rms_px < 0.1


def test_frames_of_another_exposure_have_their_own_growths():
    """The same panels at a longer exposure (or another resolution) grow further: a group of their own."""
    rng = np.random.default_rng(9)
    pairs = [(1, 2), (2, 3), (1, 3), (1, 2, 3)] * 3
    short = _frames(pairs, rng, growths_px={1: 1.5, 2: 1.8, 3: 1.2})
    long = _frames(pairs, rng, growths_px={1: 2.1, 2: 2.5, 3: 1.7})
    frames = [replace(f, growth_group=(970, 1296, 0.001)) for f in short]
    frames += [replace(f, name=f"long-{f.name}", growth_group=(970, 1296, 0.004)) for f in long]
    adjusted = adjust(frames, chain_start(frames, _sketch(ROOM, 1), 1), 1, SurveyRules())
    for beacon in ROOM.beacons[1:]:
        error = adjusted.panels[beacon.id].pose.center_m - beacon.center_m
        assert np.linalg.norm(error) < 0.5e-3, (beacon.id, error)


def test_rectangles_are_fitted_with_their_half_turn_kept_as_sketched():
    """A rectangle looks the same turned by 180 deg: the chain and the fit keep the sketch's choice (panel 3
    sketched half a turn round), and place every panel as with squares."""
    rectangles = [b.model_copy(update={"side_m": None, "width_m": 0.3, "height_m": 0.15}) for b in ROOM.beacons]
    room = ROOM.model_copy(update={"beacons": rectangles})
    frames = _frames([(1, 2), (2, 3), (1, 3), (1, 2, 3)] * 4, np.random.default_rng(5), room=room)
    sketch = _sketch(room, 1)
    turned = sketch.beacons[2].model_copy(update={"yaw_deg": sketch.beacons[2].yaw_deg + 180.0})
    sketch = sketch.model_copy(update={"beacons": [*sketch.beacons[:2], turned]})
    # a sighting carries the sketch's beacon (`server.survey.sightings`)
    frames = [
        replace(f, sightings=tuple(replace(s, beacon=sketch.beacon(s.beacon.id)) for s in f.sightings)) for f in frames
    ]
    adjusted = adjust(frames, chain_start(frames, sketch, 1), 1, SurveyRules())
    for beacon, half_turns in zip(room.beacons[1:], (0, 1), strict=True):
        estimate = adjusted.panels[beacon.id]
        assert np.linalg.norm(estimate.pose.center_m - beacon.center_m) < 0.5e-3, beacon.id
        expected = beacon.yaw_deg + 180.0 * half_turns
        assert abs((estimate.pose.yaw_deg - expected + 180.0) % 360.0 - 180.0) < 0.02, (beacon.id, estimate.pose)
    assert adjusted.rms_px < 0.1


def test_sightings_far_off_after_the_first_fit_are_left_out_and_frames_left_with_one_are_skipped():
    frames = _frames([(1, 2), (2, 3), (1, 2, 3)], np.random.default_rng(6))
    chi = ((1.0, 1.1), (1.0, 50.0), (1.0, 1.0, 40.0))  # median 1.0: the limit is 6 (outlier_factor)
    rms = tuple(tuple(0.05 * c for c in each) for each in chi)
    adjusted = Adjusted(panels={}, cameras=(), rms_px=0.1, sighting_rms_px=rms, sighting_chi=chi)
    kept, skipped = _without_outliers(frames, adjusted, SurveyRules())
    assert [f.name for f in kept] == ["f0", "f2"] and [s.name for s in skipped] == ["f1"]
    assert kept[0] is frames[0] or kept[0].sightings == frames[0].sightings
    assert [s.beacon.id for s in kept[1].sightings] == [1, 2]
    assert "left out after the first fit: beacon 3 2.00 px off" in kept[1].notes[-1]
    assert "beacon 3 2.50 px" in skipped[0].why and "6 times the median" in skipped[0].why


def test_a_panel_the_frames_do_not_tie_to_the_anchor_is_refused_naming_it_and_the_frames():
    room = ROOM.model_copy(
        update={"beacons": [*ROOM.beacons, Beacon(id=4, center_m=[0.0, 1.2, 2.7], side_m=0.2, corner_radius_m=0.02)]}
    )
    frames = _frames([(1, 2), (3, 4), (3, 4)], np.random.default_rng(2), room=room)
    with pytest.raises(SurveyRefused) as refused:
        chain_start(frames, _sketch(room, 1), 1)
    assert refused.value.beacon_id == 3
    message = refused.value.message
    assert "beacon 3 is not connected to anchor 1" in message and "'f1', 'f2'" in message
    assert "only with beacons [4]" in message and "connected beacons [1, 2]" in message


def test_a_square_turned_a_quarter_in_the_sketch_keeps_its_sketch_yaw():
    assert nearest_equivalent_deg(1.0, 91.5, 90.0) == pytest.approx(91.0)
    assert nearest_equivalent_deg(179.0, -179.0, 90.0) == pytest.approx(-181.0 + 360.0)
    assert nearest_equivalent_deg(10.0, -170.0, 180.0) == pytest.approx(-170.0)


def test_the_bearing_is_a_circular_mean_with_its_spread_and_the_shared_bias():
    turned = [rotation_z(yaw) for yaw in (0.0, 20.0, -30.0)]
    bearing = map_bearing(turned + [rotation_z(5.0)], [350.0, 345.0, 25.0, None], 0.0)  # +X at 350, 5, -5
    assert bearing is not None and bearing.frames == 3
    assert bearing.bearing_deg == pytest.approx(360.0 - 10.0 / 3.0, abs=0.01)  # across north, in [0, 360)
    spread = math.degrees(np.std(np.radians([-10, 5, -5]))) / math.sqrt(3)
    assert bearing.sigma_deg == pytest.approx(spread, rel=0.1)
    # the error every frame shares is added in quadrature: no number of frames shrinks the sigma below it
    biased = map_bearing(turned, [350.0, 345.0, 25.0], 10.0)
    assert biased.bearing_deg == bearing.bearing_deg
    assert biased.sigma_deg == pytest.approx(math.hypot(10, spread), rel=0.1)
    assert map_bearing(turned, [None, None, None], 10.0) is None
    assert map_bearing(turned[:1], [12.0], 10.0).sigma_deg is None  # one reading shows no spread


def test_the_bearings_sigma_holds_its_errors_over_40_surveys():
    """The simulator's compass (a bias shared by a survey's frames plus each frame's noise, `simulator.survey`)
    read by 40 surveys of 12 frames, the cameras' yaws exact (the survey's are good to hundredths of a
    degree): about 95 % of the bearings' errors lie within 2 of their sigmas, all within 3. Without the shared
    part in the sigma (the spread over sqrt(12) alone, ~3 degrees) only about a third did."""
    from simulator.scene import find_scene
    from simulator.survey import SurveyShots, compass_readings_deg, survey_poses

    scene, shots, rules = find_scene("office"), SurveyShots(), SurveyRules()
    ratios, spread_only = [], []
    for seed in range(40):
        rng = np.random.default_rng([seed, 4])
        poses = survey_poses(scene, 12, rng, shots)
        readings = compass_readings_deg(poses, shots, rng)
        bearing = map_bearing([p.rotation_wc for p in poses], list(readings), rules.compass_bias_sigma_deg)
        error = (bearing.bearing_deg - shots.true_bearing_deg + 180.0) % 360.0 - 180.0
        ratios.append(abs(error) / bearing.sigma_deg)
        spread_only.append(abs(error) / map_bearing([p.rotation_wc for p in poses], list(readings), 0.0).sigma_deg)
    assert np.mean(np.less(ratios, 2.0)) >= 0.9 and max(ratios) < 3.5
    assert 0.7 < np.sqrt(np.mean(np.square(ratios))) < 1.3
    assert np.mean(np.less(spread_only, 2.0)) < 0.6  # what the sigma claimed before


def test_grown_quads_move_every_side_out():
    square = np.array([[0.0, 10.0], [10.0, 10.0], [10.0, 0.0], [0.0, 0.0]])
    assert np.allclose(grown_quads(square, 1.0), [[-1, 11], [11, 11], [11, -1], [-1, -1]])
    assert np.allclose(grown_quads(square[::-1], 1.0), grown_quads(square, 1.0)[::-1])
    assert np.allclose(grown_quads(grown_quads(square, 2.0), -2.0), square)


# rendered frames of the office (4 panels, a quarter of the Mi 8's resolution)


def test_a_quarter_scale_office_is_surveyed_to_millimetres():
    truth, sketch, anchor, shots = survey_set()
    report = survey([survey_frame(s, f"frame_{k}") for k, s in enumerate(shots)], sketch, anchor, "surveyed")
    assert report.frames_used >= len(shots) - 2 and report.rms_px < 0.5
    for beacon in report.beacons:
        true = truth.beacon(beacon.beacon_id)
        error = np.subtract(beacon.center_m, true.center_m)
        assert np.linalg.norm(error) < 0.004, (beacon.beacon_id, error)  # figures at half scale: docs/survey.md
        assert abs(beacon.yaw_deg - true.yaw_deg) < 0.1
        assert beacon.frames >= 1
    assert report.map.name == "surveyed" and report.map.beacon(anchor) == sketch.beacon(anchor)
    # the compass: a 10-degree bias shared by the set plus 10 degrees a frame (docs/survey.md); this set errs by less
    assert report.bearing_deg is not None and abs((report.bearing_deg - 30.0 + 180) % 360 - 180) < 15
    assert report.map.bearing_deg == report.bearing_deg and report.bearing_sigma_deg > 0


def test_frames_are_read_one_at_a_time():
    """A generator of frames is read once, and each image is let go once its sightings are taken."""
    truth, sketch, anchor, shots = survey_set()
    images: list[weakref.ref] = []

    def frames():
        for k, shot in enumerate(shots):
            gc.collect()
            # the survey's loop still holds the frame before this one; the one before that must be gone
            assert all(image() is None for image in images[:-1]), f"frame {k}: earlier images are still held"
            frame = survey_frame(shot, f"frame_{k}")
            pixels = frame.frame.pixels.copy()  # the cached shot keeps its own
            pixels.flags.writeable = False
            images.append(weakref.ref(pixels))
            yield replace(frame, frame=replace(frame.frame, pixels=pixels))

    report = survey(frames(), sketch, anchor, "surveyed")
    assert report.frames_used >= len(shots) - 2 and len(images) == len(shots)


def test_without_compass_readings_the_map_keeps_the_sketchs_bearing():
    _, sketch, anchor, shots = survey_set()
    frames = []
    for k, shot in enumerate(shots):
        frame = survey_frame(shot, f"frame_{k}")
        meta = frame.frame.meta.model_copy(update={"compass_bearing_deg": None})
        frames.append(replace(frame, frame=replace(frame.frame, meta=meta)))
    report = survey(frames, sketch.model_copy(update={"bearing_deg": 30.0}), anchor, "surveyed")
    assert report.bearing_deg is None  # none measured
    assert report.map.bearing_deg == 30.0


def test_frames_that_see_one_panel_are_skipped_and_a_set_without_two_is_refused():
    _, sketch, anchor, shots = survey_set()
    frames = [survey_frame(s, f"frame_{k}", s.labels[:1]) for k, s in enumerate(shots[:3])]
    with pytest.raises(SurveyRefused, match="no frame sees two named panels") as refused:
        survey(frames, sketch, anchor, "surveyed")
    assert "only beacon" in refused.value.message and "a survey frame must see two or more" in refused.value.message


def test_labels_on_no_panel_are_said():
    _, sketch, anchor, shots = survey_set()
    label = shots[0].labels[0]
    nowhere = PanelLabel(beacon_id=label.beacon_id, x_px=5000.0, y_px=5000.0)  # beyond the frame
    with pytest.raises(SurveyRefused) as refused:
        survey([survey_frame(shots[0], "frame_0", [nowhere, *shots[0].labels[1:]])], sketch, anchor, "x")
    assert f"the label of beacon {label.beacon_id} at (5000, 5000) px is on no panel" in refused.value.message


def test_an_unknown_anchor_or_a_label_of_an_unknown_beacon_is_bad_input():
    _, sketch, anchor, shots = survey_set()
    frames = [survey_frame(s, f"frame_{k}") for k, s in enumerate(shots[:2])]
    with pytest.raises(SurveyInputError, match="anchor 7 is not in sketch") as wrong:
        survey(frames, sketch, 7, "x")
    assert wrong.value.field == "anchor"
    bad = [survey_frame(shots[0], "frame_0", [PanelLabel(beacon_id=5, x_px=10, y_px=10)])]
    with pytest.raises(SurveyInputError, match="names beacon 5, which is not in sketch") as wrong:
        survey(bad, sketch, anchor, "x")
    assert wrong.value.field == "samples.0.labels.0.beacon_id"


def test_the_panels_of_an_id_frame_are_named_by_their_own_stripes():
    from tests.server.test_rooms import big_panels, room_id_frame  # two 0.6 m coded panels, one cut by the border

    room = big_panels((0.62, 0.0), (-0.1, 0.0))
    seen = frame_sightings(room_id_frame(room), "id", [], room)
    assert isinstance(seen, FrameSightings), seen
    assert sorted((s.beacon.id, s.cut) for s in seen.sightings) == [(17, False), (42, True)]
    whole = next(s for s in seen.sightings if not s.cut)
    assert whole.grown and whole.sigmas_px[0] < seen.sightings[1].sigmas_px[0]


def test_a_labelled_panel_of_an_id_frame_is_measured_whole():
    """A panel whose stripes name none (a steady lamp among coded panels) is named by its label and measured
    on its own pixels (its own blob is not among the blobs the crop paints out); on an ID frame whose stripes
    cannot be read at all, the labels name the found blobs."""
    from simulator.render import Emitter, beacon_outline_px
    from tests.helpers import CAMERA
    from tests.server.test_rooms import CUT_POSE, big_panels, room_id_frame

    room = big_panels((0.62, 0.0), (-0.1, 0.0))
    coded = room_id_frame(room)
    steady = render_emitters(
        [Emitter(beacon_outline_px(room.beacons[0], CAMERA, CUT_POSE), 200.0, None)],
        *coded.pixels.shape[::-1],
        SensorModel(background_dn=0.0, plateau_dn=200.0, psf_sigma_px=1.0, read_noise_dn=0.0),
        np.random.default_rng(0),
    )
    # panel 17 steady (its blob's pixels replaced), panel 42 coded and cut by the border
    whole = steady > 1
    pixels = np.where(whole, np.maximum(steady, coded.pixels.min()), coded.pixels).astype(np.uint8)
    pixels.flags.writeable = False
    frame = replace(coded, pixels=pixels)
    x, y = beacon_outline_px(room.beacons[0], CAMERA, CUT_POSE).mean(axis=0)
    label = PanelLabel(beacon_id=17, x_px=float(x), y_px=float(y))
    seen = frame_sightings(frame, "id", [label], room)
    assert isinstance(seen, FrameSightings), seen
    assert sorted((s.beacon.id, s.cut) for s in seen.sightings) == [(17, False), (42, True)]
    unreadable = replace(frame, meta=frame.meta.model_copy(update={"rolling_shutter_skew_s": None}))
    seen = frame_sightings(unreadable, "id", [label], room)
    why = seen.why if isinstance(seen, SkippedFrame) else "; ".join(seen.notes)
    assert "its stripes cannot name panels" in why and "is on no panel" not in why, why


def test_corners_of_unevenly_blurred_sides_are_weighed_by_how_far_their_growths_lie_apart():
    from server.outcomes import Fix
    from server.survey.sightings import _sighting
    from tests.helpers import survey_frame as shot_frame

    _, sketch, _, shots = survey_set()
    frame = shot_frame(shots[0], "frame_0").frame
    beacon = sketch.beacons[0]
    corners = np.array([[400.0, 500.0], [500.0, 500.0], [500.0, 600.0], [400.0, 600.0]])
    fix = Fix(
        np.array([0.0, 0.0, 0.0]),
        np.eye(3),
        beacon.id,
        None,
        0.1,
        True,
        corners.mean(axis=0),
        corners,
        growth_px=1.2,
        uneven_px=0.4,
    )
    blob = SimpleNamespace(area_px=1e4)  # the blob is only read for its area
    rules = SurveyRules()
    even = _sighting(frame, replace(fix, uneven_px=0.0), beacon, blob, rules)  # type: ignore[arg-type]
    assert np.allclose(even.sigmas_px, [rules.corner_sigma_px] * 4 + [rules.centre_sigma_px])
    uneven = _sighting(frame, fix, beacon, blob, rules)  # type: ignore[arg-type]
    assert np.all(uneven.sigmas_px >= 0.4) and np.all(uneven.sigmas_px < 0.41)
