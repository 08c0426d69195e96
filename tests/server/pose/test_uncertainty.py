"""The position's covariance from the pose stage: its pieces, and its calibration on synthetic corners."""

import math

import cv2
import numpy as np
import pytest

from server.geometry import beacon_to_world, camera_matrix, model_corners_m, rotation_from_ypr, world_to_camera
from server.outcomes import Refusal
from server.pose.solve import (
    GravityMode,
    PoseRules,
    _centre_jacobian,
    consistency_factor,
    corner_covariance,
    side_errors,
    solve_pose,
)
from server.vision.polygon import intersect_lines
from shared_schemas import Beacon, CameraIntrinsics

CHI2_95 = 5.991  # chi-square, 2 dof, 95 %
# the Mi 8 front camera (full resolution), as in the accuracy benchmark
CAMERA = CameraIntrinsics(fx=3911.1, fy=3911.1, cx=1939.5, cy=2591.5)
K = camera_matrix(CAMERA)
BEACON = Beacon(id=0, center_m=[0.0, 0.0, 2.0], yaw_deg=20.0, side_m=0.174, corner_radius_m=0.02)


def project(position, rotation_wc, beacon=BEACON) -> np.ndarray:
    points = beacon_to_world(beacon, np.vstack([model_corners_m(beacon.side_m), np.zeros(3)]))
    pixels, _ = cv2.projectPoints(world_to_camera(points, position, rotation_wc), np.zeros(3), np.zeros(3), K, None)
    return pixels.reshape(-1, 2)


def lines_of(corners: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Side k as (point, unit outward normal) through corners k and k + 1."""
    centre = corners.mean(axis=0)
    result = []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        d = (b - a) / np.linalg.norm(b - a)
        n = np.array([d[1], -d[0]])
        result.append((a, n if n @ ((a + b) / 2 - centre) > 0 else -n))
    return result


def test_centre_jacobian_matches_finite_differences():
    corners = project(np.array([0.4, -0.3, 0.0]), rotation_from_ypr(30.0, 6.0, -4.0))[:4]
    numeric = np.zeros((2, 8))
    for i in range(8):
        moved = corners.copy().ravel()
        moved[i] += 1e-4
        c = moved.reshape(4, 2)
        numeric[:, i] = (intersect_lines(c[0], c[2], c[1], c[3]) - intersect_lines(*corners[[0, 2, 1, 3]])) / 1e-4
    np.testing.assert_allclose(_centre_jacobian(corners), numeric, atol=1e-6)


def test_corner_covariance_is_that_of_moved_and_turned_sides():
    """Monte Carlo of the model itself: each side shifted and turned about its middle, all four
    moved in by a growth that is off by its own error and by the coupling times their mean shift."""
    corners = project(np.array([0.5, 0.2, 0.0]), rotation_from_ypr(-25.0, 5.0, 3.0))[:4]
    errors = side_errors(corners, BEACON, 0.01, growth_sigma_px=0.03)
    sides, growth = corner_covariance(corners, errors)
    rng = np.random.default_rng(4)
    lines = lines_of(corners)
    lengths = [np.linalg.norm(corners[(k + 1) % 4] - corners[k]) for k in range(4)]
    samples = []
    for _ in range(20000):
        shift = rng.normal(0, math.hypot(errors.side_sigma, errors.locking_sigma), 4)
        turn = rng.normal(0, errors.side_sigma * math.sqrt(12) / errors.fit_fraction, 4)  # end to end, px
        measured_growth = rng.normal(0, errors.growth_sigma) + errors.growth_coupling * shift.mean()
        moved = []
        for k, (point, normal) in enumerate(lines):
            middle = point + (corners[(k + 1) % 4] - point) / 2
            direction = np.array([-normal[1], normal[0]])
            angle = turn[k] / lengths[k]
            new_direction = direction * math.cos(angle) + normal * math.sin(angle)
            moved.append((middle + (shift[k] - measured_growth) * normal, new_direction))
        new_corners = []
        for k in range(4):
            (p, d), (q, e) = moved[(k - 1) % 4], moved[k]
            s = np.linalg.solve(np.column_stack([d, -e]), q - p)
            new_corners.append(p + s[0] * d)
        samples.append((np.array(new_corners) - corners).ravel())
    empirical = np.cov(np.array(samples).T)
    model = sides + growth
    scale = np.sqrt(np.outer(np.diag(model), np.diag(model)))
    np.testing.assert_allclose(empirical / scale, model / scale, atol=0.04)


def test_growth_sigma_follows_the_arc_crossings():
    """The growth's error from the arcs' crossings: larger for a smaller panel image (fewer arc
    crossings), and the coupling of a 0.115 corner radius / side panel is 2 (1 + 1/sqrt 2) / 0.77."""
    near = project(np.array([0.1, 0.1, 1.0]), np.eye(3))[:4]
    far = project(np.array([0.1, 0.1, -1.0]), np.eye(3))[:4]  # 3 m below
    near_errors, far_errors = side_errors(near, BEACON, 0.002), side_errors(far, BEACON, 0.002)
    assert 0.015 < near_errors.growth_sigma < far_errors.growth_sigma < 0.035
    assert near_errors.growth_coupling == pytest.approx(2 * (1 + math.sqrt(0.5)) / (1 - 2 * 0.02 / 0.174))
    assert side_errors(near, BEACON, 0.002, growth_sigma_px=0.05).growth_sigma == 0.05


def test_pixel_locking_offset_only_when_no_side_crosses_the_pixel_grid():
    square = project(np.array([0.0, 0.0, 0.0]), rotation_from_ypr(20.0, 0.0, 0.0))[:4]  # face to face, on the grid
    assert side_errors(square, BEACON, 0.002).locking_sigma == PoseRules().pixel_locking_sigma_px
    turned = project(np.array([0.0, 0.0, 0.0]), rotation_from_ypr(25.0, 0.0, 0.0))[:4]
    assert side_errors(turned, BEACON, 0.002).locking_sigma == 0.0


def sample_corners(rng, corners: np.ndarray, sides: np.ndarray, growth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    noise = rng.multivariate_normal(np.zeros(8), sides + growth)
    noisy = corners + noise.reshape(4, 2)
    return noisy, intersect_lines(noisy[0], noisy[2], noisy[1], noisy[3])


@pytest.mark.parametrize("mode", list(GravityMode))
def test_ellipse_holds_95_percent_of_the_errors_of_corners_drawn_from_the_model(mode):
    """Corners drawn from the noise model (growth and side errors), the centre computed from
    them as the pipeline does, gravity with its sensor error: the fix's 2D error lies inside
    the reported 95 % ellipse in 95 % of the draws, whatever the mode."""
    rng = np.random.default_rng(11)
    position = np.array([0.6, -0.4, 0.0])
    rotation = rotation_from_ypr(35.0, 4.0, -6.0)
    exact = project(position, rotation)[:4]
    side_sigma, gravity_sigma = 0.01, 0.1
    sides, growth = corner_covariance(exact, side_errors(exact, BEACON, side_sigma))
    inside, draws = 0, 300
    for _ in range(draws):
        corners, centre = sample_corners(rng, exact, sides, growth)
        error = rotation_from_ypr(0.0, *rng.normal(0.0, gravity_sigma, 2))
        gravity = rotation.T @ error @ np.array([0.0, 0.0, -1.0])
        pose = solve_pose(corners, centre, BEACON, K, gravity, gravity_sigma, mode, side_sigma)
        assert not isinstance(pose, Refusal)
        d = (pose.position_m - position)[:2]
        inside += d @ np.linalg.solve(pose.covariance_m2[:2, :2], d) <= CHI2_95
    assert 0.92 <= inside / draws <= 0.98


def test_covariance_is_a_covariance_and_leaves_the_pose_alone():
    position, rotation = np.array([0.3, 0.2, 0.0]), rotation_from_ypr(10.0, 3.0, 2.0)
    points = project(position, rotation)
    for mode in GravityMode:
        pose = solve_pose(points[:4], points[4], BEACON, K, rotation.T @ [0, 0, -1.0], 0.1, mode, 0.005)
        covariance = pose.covariance_m2
        assert covariance.shape == (3, 3) and np.all(np.isfinite(covariance))
        np.testing.assert_allclose(covariance, covariance.T)
        assert np.linalg.eigvalsh(covariance).min() > 0
        np.testing.assert_allclose(pose.position_m, position, atol=1e-6)
    vision = solve_pose(points[:4], points[4], BEACON, K, gravity_mode=GravityMode.never, corner_sigma_px=0.005)
    always = solve_pose(points[:4], points[4], BEACON, K, rotation.T @ [0, 0, -1.0], 0.1, GravityMode.always, 0.005)
    # 2 m below the panel a 0.1 degree sensor puts the fix ~3.5 mm off; vision knows it far better
    assert 2.5e-3 < math.sqrt(always.covariance_m2[0, 0]) < 5e-3
    assert math.sqrt(vision.covariance_m2[0, 0]) < 1e-3


def test_corners_no_view_of_the_panel_explains_scale_the_sides_noise():
    position, rotation = np.array([0.3, 0.2, 0.0]), rotation_from_ypr(10.0, 3.0, 2.0)
    points = project(position, rotation)
    calm = solve_pose(points[:4], points[4], BEACON, K, gravity_mode=GravityMode.never, corner_sigma_px=0.005)
    assert calm.consistency_factor == 1.0
    bent = points.copy()
    bent[0] += [0.3, 0.0]  # one corner 0.3 px off: no pose puts all four where they are
    centre = intersect_lines(bent[0], bent[2], bent[1], bent[3])
    pose = solve_pose(bent[:4], centre, BEACON, K, gravity_mode=GravityMode.never, corner_sigma_px=0.005)
    assert pose.consistency_factor > 10
    assert np.trace(pose.covariance_m2) > 3 * np.trace(calm.covariance_m2)
    strict = PoseRules(consistency_scaling=False)
    plain = solve_pose(bent[:4], centre, BEACON, K, None, 0.1, GravityMode.never, 0.005, strict)
    assert plain.consistency_factor == 1.0


def test_consistency_chi_square_has_two_degrees_of_freedom():
    """Under the model the chi-square of the corners against the best pose averages 2."""
    rng = np.random.default_rng(5)
    position, rotation = np.array([0.3, 0.2, 0.0]), rotation_from_ypr(10.0, 3.0, 2.0)
    exact = project(position, rotation)[:4]
    sides, growth = corner_covariance(exact, side_errors(exact, BEACON, 0.01))
    object_points = model_corners_m(BEACON.side_m)
    rvec, tvec = cv2.solvePnP(object_points, exact, K, None, flags=cv2.SOLVEPNP_IPPE_SQUARE)[1:]
    projected, jacobian = cv2.projectPoints(object_points, rvec, tvec, K, None)
    values = []
    for _ in range(2000):
        noisy = exact + rng.multivariate_normal(np.zeros(8), sides + growth).reshape(4, 2)
        values.append(2 * consistency_factor(projected.ravel() - noisy.ravel(), jacobian[:, :6], sides + growth))
    assert np.mean(values) == pytest.approx(2.0, rel=0.1)
