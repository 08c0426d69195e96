"""Undoing the rolling shutter's skew of a turning camera with the frame's gyroscope rate (issue 13
item 3): hand tremor of ~1 deg/s shears the panel by its readout, which the pose fit took as a tilt.

Frames: the robustness bench's "tremor" cell (1 deg/s per axis RMS) at 1 m, quarter resolution,
whose metadata carries the drawn rate in the camera frame with a 0.1 deg/s bias per axis.
"""

from dataclasses import replace

import cv2
import numpy as np
import pytest

from server.camera import intrinsics_from_profile
from server.geometry import camera_matrix
from server.ingest import LumaFrame
from server.locator import locate
from server.vision.readout import undo_readout_turn
from shared_schemas import device_profiles
from simulator.benchmarks import AccuracyConfig, accuracy_frame, bench_motion, position_seen_m
from simulator.chain import ChainSpec
from simulator.fixtures import fixture_meta
from simulator.motion import MotionSpec
from simulator.render import CameraPose, ReadoutMotion, world_polygon_px

TREMOR = replace(AccuracyConfig(distance_m=1.0, frames=40, scale=0.25, seed=1),
                 chain=ChainSpec(motion=MotionSpec.tremor()))


def test_a_square_read_while_turning_comes_back_as_seen_at_one_instant():
    camera = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], 970, 1296)
    pose = CameraPose(position_m=np.array([0.1, -0.05, 0.0]), rotation_wc=np.eye(3))
    square = np.array([[-0.2, -0.2, 1.0], [0.2, -0.2, 1.0], [0.2, 0.2, 1.0], [-0.2, 0.2, 1.0]])
    row_time_s, omega_dps = 0.03 / 1295, np.array([30.0, -20.0, 50.0])  # the map frame is the camera's here
    turning = ReadoutMotion(np.zeros(3), omega_dps, row_time_s, 0.0)
    read = world_polygon_px(square, camera, pose, 970, 1296, max_step_px=1e9, motion=turning)
    meta = fixture_meta(camera, 970, 1296, pose, rolling_shutter_skew_s=0.03,
                        angular_velocity_camera_dps=omega_dps.tolist())
    undone = undo_readout_turn(read, camera_matrix(camera), meta)
    # the camera at the instant the mean row was read
    instant = float(read[:, 1].mean()) * row_time_s
    still = world_polygon_px(square, camera, CameraPose(pose.position_m, _turned(omega_dps, instant)), 970, 1296,
                             max_step_px=1e9)
    assert np.abs(read - still).max() > 1.0  # the skew is pixels
    assert np.abs(undone - still).max() < 0.02


def _turned(omega_dps: np.ndarray, seconds: float) -> np.ndarray:
    rotation, _ = cv2.Rodrigues(np.radians(omega_dps) * seconds)
    return rotation


def test_no_rate_leaves_the_points_alone():
    camera = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], 970, 1296)
    points = np.array([[100.0, 200.0], [300.0, 900.0]])
    meta = fixture_meta(camera, 970, 1296, CameraPose(np.zeros(3), np.eye(3)), rolling_shutter_skew_s=0.03)
    assert np.array_equal(undo_readout_turn(points, camera_matrix(camera), meta), points)


@pytest.mark.parametrize("index", [0, 3])
def test_tremor_costs_little_once_the_gyroscope_is_heard(index):
    frame, beacon_map, pose = accuracy_frame(TREMOR, index)
    seen = position_seen_m(pose, bench_motion(TREMOR, index, frame.meta.height), frame.camera,
                           beacon_map.beacons[0].center_m)
    deaf = LumaFrame(frame.pixels, frame.meta.model_copy(update={"angular_velocity_camera_dps": None}), frame.camera)
    errors = []
    for each in (frame, deaf):
        result = locate(each, beacon_map)
        assert result.ok, result.message
        errors.append(1000 * float(np.hypot(*np.subtract(result.position_m, seen)[:2])))
    # frames 0 and 3: 3.9 and 2.6 mm without the rate, 0.7 and 0.5 mm with it
    assert errors[0] < 1.0 and errors[1] > 2 * errors[0], errors


def test_a_turn_no_frame_survives_is_not_undone():
    # 4000 deg/s (the contract's bound) over a 30 ms readout would turn rays behind the camera
    camera = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], 970, 1296)
    points = np.array([[100.0, 100.0], [900.0, 1200.0]])
    meta = fixture_meta(camera, 970, 1296, CameraPose(np.zeros(3), np.eye(3)), rolling_shutter_skew_s=0.03,
                        angular_velocity_camera_dps=[4000.0, 0.0, 0.0])
    assert np.array_equal(undo_readout_turn(points, camera_matrix(camera), meta), points)
