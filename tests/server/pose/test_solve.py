"""Pose stage: exact corners of a known pose must give that pose back (fixed seed)."""

import math

import cv2
import numpy as np
import pytest

from server.geometry import (
    beacon_to_world,
    camera_matrix,
    model_corners_m,
    orthonormal_pair,
    rotation_from_ypr,
    rotation_z,
    world_to_camera,
    ypr_from_rotation,
)
from server.outcomes import Refusal
from server.pose.ordering import order_corners
from server.pose.solve import (
    GravityMode,
    PoseRules,
    _camera_in_map,
    _map_pose,
    _map_residuals,
    _vision_pose,
    beacon_frame,
    pose_with_gravity,
    solve_pose,
)
from shared_schemas import Beacon, CameraIntrinsics, FailureReason, OrientationRule

CAMERA = CameraIntrinsics(fx=977.78, fy=977.78, cx=484.5, cy=647.5)
K = camera_matrix(CAMERA)


def project(beacon: Beacon, position, rotation_wc) -> tuple[np.ndarray, np.ndarray]:
    points = beacon_to_world(beacon, np.vstack([model_corners_m(beacon.side_m), np.zeros(3)]))
    camera_points = world_to_camera(points, position, rotation_wc)
    pixels, _ = cv2.projectPoints(camera_points, np.zeros(3), np.zeros(3), K, None)
    pixels = pixels.reshape(-1, 2)
    return pixels[:4], pixels[4]


def gravity_of(rotation_wc) -> np.ndarray:
    return rotation_wc.T @ np.array([0.0, 0.0, -1.0])


@pytest.mark.parametrize("seed", range(8))
def test_exact_corners_give_the_pose_back(seed):
    rng = np.random.default_rng(seed)
    beacon = Beacon(id=3, center_m=[0.4, -0.2, 2.5], yaw_deg=rng.uniform(-180, 180), side_m=0.174, corner_radius_m=0.02)
    position = np.array([*(np.array(beacon.center_m[:2]) + rng.uniform(-0.3, 0.3, 2)), 1.2])
    yaw = beacon.yaw_deg + rng.uniform(-40, 40)
    rotation = rotation_from_ypr(yaw, *rng.uniform(-10, 10, 2))
    corners, center = project(beacon, position, rotation)
    shuffled = np.roll(corners, rng.integers(4), axis=0)[:: 1 if rng.integers(2) else -1]
    ordered = order_corners(shuffled, beacon.yaw_deg, heading_deg=None)
    assert ordered.rule is OrientationRule.yaw_within_45deg
    np.testing.assert_allclose(ordered.corners, corners, atol=1e-9)
    for mode in GravityMode:
        pose = solve_pose(ordered.corners, center, beacon, K, gravity_of(rotation), gravity_mode=mode)
        assert not isinstance(pose, Refusal), pose
        np.testing.assert_allclose(pose.position_m, position, atol=1e-6)
        np.testing.assert_allclose(pose.rotation_wc, rotation, atol=1e-6)
        assert pose.gravity_used is (mode is not GravityMode.never)
        assert pose.reprojection_error_px < 1e-6


def test_heading_picks_the_quarter_turn():
    beacon = Beacon(id=0, center_m=[0, 0, 1.0], yaw_deg=0.0, side_m=0.174)
    rotation = rotation_from_ypr(120.0, 2.0, -1.0)  # outside the +-45 degree default rule
    corners, center = project(beacon, np.zeros(3), rotation)
    wrong = order_corners(corners, beacon.yaw_deg, heading_deg=None)
    right = order_corners(corners, beacon.yaw_deg, heading_deg=115.0)
    assert right.rule is OrientationRule.heading
    np.testing.assert_allclose(right.corners, corners, atol=1e-9)
    assert not np.allclose(wrong.corners, corners)
    pose = solve_pose(right.corners, center, beacon, K)
    assert abs(ypr_from_rotation(pose.rotation_wc)[0] - 120.0) < 1e-6


def test_gravity_prior_fixes_the_tilt_it_is_given():
    beacon = Beacon(id=0, center_m=[0, 0, 3.0], side_m=0.174)
    rotation = rotation_from_ypr(10.0, 4.0, -3.0)
    corners, center = project(beacon, np.array([0.3, 0.1, 0.0]), rotation)
    tilted = rotation_from_ypr(0.0, 0.5, 0.0) @ rotation  # gravity 0.5 degree off
    position, rotation_wc = pose_with_gravity(np.vstack([corners, center]), beacon, K, gravity_of(tilted))
    # A 0.5 degree tilt error moves a camera 3 m below the beacon by about 3 m * tan(0.5 deg).
    lateral = np.hypot(*(position[:2] - [0.3, 0.1]))
    assert lateral == pytest.approx(3.0 * math.tan(math.radians(0.5)), rel=0.15)
    np.testing.assert_allclose(rotation_wc.T @ [0, 0, -1.0], gravity_of(tilted), atol=1e-9)


def test_ambiguous_far_square_is_refused_without_gravity_and_decided_with_it():
    beacon = Beacon(id=0, center_m=[0, 0, 6.0], side_m=0.174)
    rotation = rotation_from_ypr(0.0, 25.0, 0.0)
    corners, center = project(beacon, np.array([2.6, 0.0, 0.0]), rotation)
    rng = np.random.default_rng(0)
    noisy = corners + rng.normal(0, 0.1, corners.shape)  # a 28 px panel measured coarsely
    refused = solve_pose(noisy, center, beacon, K, gravity_mode=GravityMode.never)
    assert isinstance(refused, Refusal) and refused.reason is FailureReason.pose_ambiguous
    decided = solve_pose(noisy, center, beacon, K, gravity_camera=gravity_of(rotation))
    assert not isinstance(decided, Refusal) and decided.gravity_used
    assert np.linalg.norm(decided.position_m - [2.6, 0, 0]) < 0.15


def test_map_jacobian_matches_finite_differences():
    beacon = Beacon(id=0, center_m=[0, 0, 2.0], side_m=0.174)
    rotation = rotation_from_ypr(20.0, 6.0, -4.0)
    corners, center = project(beacon, np.array([0.2, -0.1, 0.0]), rotation)
    objects = np.vstack([model_corners_m(beacon.side_m), np.zeros(3)])
    images = (np.vstack([corners, center]) + 0.3).reshape(-1)
    params = np.array([0.1, -0.05, 0.3, 0.02, -0.01, 2.0])
    across = orthonormal_pair(np.array([0.05, -0.02, -1.0]) / np.linalg.norm([0.05, -0.02, -1.0])).tolist()
    weights = (1 / 0.05, 1 / np.radians(0.1))
    _, analytic = _map_residuals(params, objects, images, K, across, weights)
    numeric = np.zeros_like(analytic)
    for i in range(6):
        step = np.zeros(6)
        step[i] = 1e-7
        plus, _ = _map_residuals(params + step, objects, images, K, across, weights)
        minus, _ = _map_residuals(params - step, objects, images, K, across, weights)
        numeric[:, i] = (plus - minus) / 2e-7
    np.testing.assert_allclose(analytic, numeric, rtol=1e-4, atol=1e-3 * np.abs(analytic).max())


def tilt_error_deg(rotation_wc, truth) -> float:
    down = np.array([0.0, 0.0, -1.0])
    return math.degrees(math.acos(np.clip((rotation_wc.T @ down) @ (truth.T @ down), -1, 1)))


def test_map_prior_weighs_vision_and_gravity_by_what_each_knows():
    rng = np.random.default_rng(3)
    rotation = rotation_from_ypr(15.0, 5.0, -3.0)
    # near and large: exact corners, gravity 0.5 degree off -> the tilt stays with vision
    near = Beacon(id=0, center_m=[0, 0, 0.6], side_m=0.174)
    corners, center = project(near, np.array([0.1, 0.05, 0.0]), rotation)
    wrong_gravity = gravity_of(rotation_from_ypr(0.0, 0.5, 0.0) @ rotation)
    pose = solve_pose(corners, center, near, K, wrong_gravity, 0.1, GravityMode.auto, 0.01)
    assert pose.gravity_used and tilt_error_deg(pose.rotation_wc, rotation) < 0.05
    always = solve_pose(corners, center, near, K, wrong_gravity, 0.1, GravityMode.always, 0.01)
    assert tilt_error_deg(always.rotation_wc, rotation) == pytest.approx(0.5, abs=0.01)
    # far and small, corners to 0.1 px, exact gravity -> the tilt follows gravity
    far = Beacon(id=0, center_m=[0, 0, 3.0], side_m=0.174)
    corners, center = project(far, np.array([0.6, -0.4, 0.0]), rotation)
    noisy = corners + rng.normal(0, 0.1, corners.shape)
    vision = solve_pose(noisy, center, far, K, None, 0.1, GravityMode.never, 0.1)
    fused = solve_pose(noisy, center, far, K, gravity_of(rotation), 0.1, GravityMode.auto, 0.1)
    # vision's tilt is ~0.5 degree uncertain here, the sensor's 0.1: the fit keeps ~4 % of vision's error
    assert tilt_error_deg(fused.rotation_wc, rotation) < min(0.1, tilt_error_deg(vision.rotation_wc, rotation) / 5)
    assert np.linalg.norm(fused.position_m - [0.6, -0.4, 0]) < np.linalg.norm(vision.position_m - [0.6, -0.4, 0])


@pytest.mark.parametrize("seed", range(6))
def test_map_fit_from_ippe_reaches_the_minimum_the_vision_pose_starts_it_at(seed):
    # the MAP fit starts from IPPE_SQUARE's best minimum, not SQPnP + LM: the same fix (speed, issue 30)
    rng = np.random.default_rng(seed)
    beacon = Beacon(id=0, center_m=[0, 0, rng.uniform(1.0, 3.0)], side_m=0.174)
    rotation = rotation_from_ypr(rng.uniform(-40, 40), *rng.uniform(-10, 10, 2))
    corners, center = project(beacon, np.array([*rng.uniform(-0.5, 0.5, 2), 0.0]), rotation)
    corners = corners + rng.normal(0, 0.05, corners.shape)
    gravity = gravity_of(rotation_from_ypr(0.0, *rng.normal(0, 0.1, 2)) @ rotation)
    pose = solve_pose(corners, center, beacon, K, gravity, 0.1, GravityMode.auto, 0.05)
    object_points = np.vstack([model_corners_m(beacon.side_m), np.zeros(3)])
    image_points = np.vstack([corners, center])
    vision = _vision_pose(object_points, image_points, K)
    try_level = pose.ambiguity_ratio > PoseRules().max_ambiguity_ratio / 4
    rvec, tvec = _map_pose(object_points, image_points, vision, beacon, K, gravity, 0.05, 0.1, try_level)
    position, _ = _camera_in_map(beacon, rvec, tvec)
    np.testing.assert_allclose(pose.position_m, position, atol=1e-9)


# Corners the pipeline measured at commit 64752c6 on two face-to-face frames of
# `lumipose bench distance` (full-resolution Mi 8 front camera): an exactly square,
# axis-aligned image, where IPPE_SQUARE's closed form returns NaN poses.
FACE_TO_FACE_K = np.array([[3911.1111111111113, 0.0, 1939.5], [0.0, 3911.1111111111113, 2591.5], [0.0, 0.0, 1.0]])
FACE_TO_FACE_CORNERS = {
    1.7: [
        [956.053686884913, 2791.946270314395],
        [1356.9463687501868, 2791.9462743756853],
        [1356.946366919429, 2391.0537193573796],
        [956.0536800437734, 2391.053733396644],
    ],
    2.1: [
        [1777.2356524691281, 4940.764348385068],
        [2101.764347760772, 4940.764347785786],
        [2101.7643477333822, 4616.235651757382],
        [1777.2356520030137, 4616.23565233638],
    ],
}


@pytest.mark.parametrize("height_m", sorted(FACE_TO_FACE_CORNERS))
def test_face_to_face_square_gives_a_finite_ambiguity_ratio(height_m):
    corners = np.array(FACE_TO_FACE_CORNERS[height_m])
    beacon = Beacon(id=0, center_m=[0, 0, height_m], side_m=0.174, corner_radius_m=0.02)
    raw = cv2.solvePnPGeneric(
        model_corners_m(beacon.side_m), corners, FACE_TO_FACE_K, None, flags=cv2.SOLVEPNP_IPPE_SQUARE
    )[3]
    assert not np.all(np.isfinite(raw))  # the degenerate case this test is about
    for mode in GravityMode:
        pose = solve_pose(
            corners, corners.mean(axis=0), beacon, FACE_TO_FACE_K, np.array([0.0, 0.0, -1.0]), gravity_mode=mode
        )
        assert not isinstance(pose, Refusal), pose
        # off the panel's axis the second minimum is far worse: not ambiguous
        assert np.isfinite(pose.ambiguity_ratio) and pose.ambiguity_ratio < 0.01
        assert np.isfinite(pose.alternative_distance_m)
        assert abs(pose.position_m[2]) < 0.01  # the camera is at height 0


def test_beacon_frame_keeps_the_sign_of_a_zero():
    # cached by the floats' bits: after a beacon at 0.0 one at -0.0 gets its own numbers, as uncached
    first = beacon_frame(Beacon(id=91, center_m=[0.0, 0.0, 3.0], side_m=0.2, yaw_deg=0.0))
    second = beacon_frame(Beacon(id=92, center_m=[-0.0, 0.0, 3.0], side_m=0.2, yaw_deg=-0.0))
    assert math.copysign(1, first[1][0]) == 1 and math.copysign(1, second[1][0]) == -1
    assert np.array_equal(np.signbit(second[0]), np.signbit(rotation_z(-0.0)))


def test_order_corners_turns_nan_corners_as_before():
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [np.nan, 1.0]])
    # no signed area: turned round, as before issue 30's plain floats (kept only when the area is negative)
    ordered = order_corners(corners, 0.0, None).corners
    assert any(np.array_equal(ordered, np.roll(corners[::-1], k, axis=0), equal_nan=True) for k in range(4))
