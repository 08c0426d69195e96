"""The survey frames' poses, labels and compass readings (`simulator.survey`): geometry only, no rendering."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from server.geometry import camera_matrix, world_to_camera, wrap_deg
from simulator.render import beacon_outline_px
from simulator.scene import find_scene
from simulator.survey import SurveyShots, compass_reading_deg, compass_readings_deg, labels_for, sketch_of, survey_poses


@pytest.mark.parametrize("scene_name", ["office", "office-9"])
def test_poses_are_hand_held_from_the_floor_with_two_panels_in_view(scene_name):
    scene = find_scene(scene_name)
    shots = SurveyShots()
    camera = scene.camera.intrinsics()
    width, height = scene.camera.frame_size()
    for pose in survey_poses(scene, 20, np.random.default_rng(4), shots):
        assert shots.heights_m[0] <= pose.position_m[2] <= shots.heights_m[1]
        tilt = math.degrees(math.acos(pose.rotation_wc[2, 2]))  # the optical axis from the vertical
        assert tilt <= shots.max_tilt_deg + 1e-6
        assert np.allclose(pose.rotation_wc.T @ pose.rotation_wc, np.eye(3)) and np.linalg.det(pose.rotation_wc) > 0
        centres = world_to_camera(np.array([b.center_m for b in scene.beacons]), pose.position_m, pose.rotation_wc)
        pixels = centres @ camera_matrix(camera).T
        pixels = pixels[:, :2] / pixels[:, 2:]
        inside = (pixels[:, 0] > 0) & (pixels[:, 0] < width) & (pixels[:, 1] > 0) & (pixels[:, 1] < height)
        assert inside.sum() >= 2
        labels = labels_for(scene, pose, shots)
        assert len(labels) >= 2
        for label in labels:  # each label's pixel lies inside its own panel's image, in the frame
            beacon = scene.beacon_map().beacon(label.beacon_id)
            outline = beacon_outline_px(beacon, camera, pose).astype(np.float32)
            assert cv2.pointPolygonTest(outline, (label.x_px, label.y_px), False) >= 0
            assert label.x_px < width and label.y_px < height


def test_the_compass_reads_the_true_bearing_minus_the_camera_yaw():
    scene = find_scene("office")
    exact = SurveyShots(true_bearing_deg=30.0, compass_bias_sigma_deg=0.0, compass_noise_sigma_deg=0.0)
    for pose in survey_poses(scene, 5, np.random.default_rng(5), exact):
        yaw = math.degrees(math.atan2(pose.rotation_wc[1, 0], pose.rotation_wc[0, 0]))
        reading = compass_reading_deg(pose, exact, np.random.default_rng(0))
        assert 0 <= reading < 360 and wrap_deg(yaw + reading - 30.0) == pytest.approx(0.0, abs=1e-9)


def test_the_compass_readings_of_one_survey_share_a_bias():
    """A building's steel deflects every reading of one survey alike: the mean error of 24 frames is not
    averaged away (it scatters from survey to survey by the bias's 10 degrees, not 14 / sqrt(24) = 2.9),
    while each frame still scatters about it by its own 10 degrees."""
    scene, shots = find_scene("office"), SurveyShots()
    means, spreads = [], []
    for seed in range(40):
        rng = np.random.default_rng(seed)
        poses = survey_poses(scene, 24, rng, shots)
        errors = [wrap_deg(reading - (shots.true_bearing_deg - math.degrees(math.atan2(p.rotation_wc[1, 0],
                                                                                       p.rotation_wc[0, 0]))))
                  for p, reading in zip(poses, compass_readings_deg(poses, shots, rng), strict=True)]
        means.append(np.mean(errors))
        spreads.append(np.std(errors, ddof=1))
    assert 7.0 < np.std(means, ddof=1) < 13.5  # the shared bias, 10 degrees
    assert 8.5 < np.mean(spreads) < 11.5  # each frame's own noise, 10 degrees


def test_a_sketch_keeps_the_anchor_and_moves_the_others():
    truth = find_scene("office").beacon_map()
    sketch = sketch_of(truth, 17, np.random.default_rng(1), error_m=0.05, yaw_error_deg=5.0)
    assert sketch.beacon(17) == truth.beacon(17)
    for beacon in truth.beacons[1:]:
        moved = sketch.beacon(beacon.id)
        assert 0 < np.linalg.norm(np.subtract(moved.center_m, beacon.center_m)) < 0.3
        assert moved.yaw_deg != beacon.yaw_deg and moved.side_m == beacon.side_m
