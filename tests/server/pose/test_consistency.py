"""The consistency stage: a fix's residuals against the noise its fit measured, as a chi-square."""

import numpy as np
import pytest

from server.geometry import rotation_from_ypr
from server.outcomes import Refusal
from server.pose.consistency import Consistency, ConsistencyRules, FitResiduals, check_fit, chi_square
from server.pose.solve import GravityMode, corner_covariance, side_errors, solve_pose
from server.vision.polygon import intersect_lines
from shared_schemas import Beacon, FailureReason
from tests.server.pose.test_uncertainty import BEACON, K, project

POSITION, ROTATION = np.array([0.3, 0.2, 0.0]), rotation_from_ypr(10.0, 3.0, 2.0)
GRAVITY = ROTATION.T @ np.array([0.0, 0.0, -1.0])
GRAVITY_SIGMA_DEG = 0.1


def _noisy_fit(rng, mode: GravityMode, sigma_px: float = 0.01):
    """solve_pose on the exact corners moved by noise drawn from the model's own covariance, with
    the gravity sensor off by its own sigma."""
    exact = project(POSITION, ROTATION)[:4]
    sides, growth = corner_covariance(exact, side_errors(exact, BEACON, sigma_px))
    corners = exact + rng.multivariate_normal(np.zeros(8), sides + growth).reshape(4, 2)
    centre = intersect_lines(corners[0], corners[2], corners[1], corners[3])
    tilted = ROTATION @ rotation_from_ypr(0.0, *rng.normal(0.0, GRAVITY_SIGMA_DEG, 2))
    gravity = None if mode is GravityMode.never else tilted.T @ np.array([0.0, 0.0, -1.0])
    return solve_pose(corners, centre, BEACON, K, gravity, GRAVITY_SIGMA_DEG, mode, sigma_px)


@pytest.mark.parametrize(("mode", "dof"), [(GravityMode.never, 2), (GravityMode.auto, 4), (GravityMode.always, 4)])
def test_noise_as_measured_passes_with_the_right_degrees_of_freedom(mode, dof):
    """Corners and sensor as noisy as their models say: the chi-square averages its degrees of
    freedom whether the fit weighed the sensor or took its tilt, and none of 300 fixes is refused."""
    rng = np.random.default_rng(3)
    found = []
    for _ in range(300):
        pose = _noisy_fit(rng, mode)
        judged = check_fit(pose.residuals, BEACON)
        assert isinstance(judged, Consistency), judged
        found.append(judged)
    assert {f.dof for f in found} == {dof}
    assert np.mean([f.chi_square for f in found]) == pytest.approx(dof, rel=0.15)


def test_residuals_ten_sigma_off_fail():
    """Residuals 10 sigma from every fit (chi-square 100, 4 degrees of freedom: p 2e-20) are refused;
    the same direction at 2 sigma passes."""
    rng = np.random.default_rng(7)
    jacobian = rng.normal(size=(10, 6))
    covariance = np.diag(rng.uniform(0.5, 2.0, 10) ** 2)
    # a direction no parameter step explains: orthogonal to the columns of S^-1/2 J, in whitened units
    whiten = np.diag(1.0 / np.sqrt(np.diag(covariance)))
    basis, _ = np.linalg.qr(whiten @ jacobian, mode="complete")
    unexplained = basis[:, 6]
    for sigmas, refused in ((10.0, True), (2.0, False)):
        residuals = np.linalg.solve(whiten, sigmas * unexplained)
        value, dof = chi_square(residuals, covariance, jacobian)
        assert (value, dof) == (pytest.approx(sigmas**2), 4)
        judged = check_fit(FitResiduals(residuals, covariance, jacobian, 8), BEACON, STATISTICS_ONLY)
        assert isinstance(judged, Refusal) is refused
    # what a step in the parameters explains costs nothing
    explained = jacobian @ rng.normal(size=6) * 100
    assert chi_square(explained, covariance, jacobian)[0] == pytest.approx(0.0, abs=1e-6)


# the chi-square alone, without the floor for what the noise model does not hold yet
STATISTICS_ONLY = ConsistencyRules(min_rms_px=0.0)


def test_a_wrong_corner_radius_is_a_shape_mismatch():
    """The corners of a 0.174 m panel seen as one with twice its corner radius: the sides' stage
    would move them by the growth the arcs imply; here, more simply, one corner 0.3 px off where
    the sides measured 0.005 px (no view of the panel explains it)."""
    bent = project(POSITION, ROTATION)
    bent[0] += [0.3, 0.0]
    centre = intersect_lines(bent[0], bent[2], bent[1], bent[3])
    pose = solve_pose(bent[:4], centre, BEACON, K, GRAVITY, GRAVITY_SIGMA_DEG, GravityMode.auto, 0.005)
    judged = check_fit(pose.residuals, BEACON, STATISTICS_ONLY)
    assert isinstance(judged, Refusal) and judged.reason is FailureReason.shape_mismatch
    assert "map beacon 0's shape (0.174 m, corner radius 0.02 m)" in judged.message
    assert "for 4 degrees of freedom" in judged.message
    assert isinstance(check_fit(pose.residuals, BEACON, ConsistencyRules(check=False)), Consistency)
    # by default 0.3 px is within what the noise model does not hold yet (a moving camera's skew): passed
    assert isinstance(check_fit(pose.residuals, BEACON), Consistency)
    far = project(POSITION, ROTATION)
    far[0] += [15.0, 0.0]
    centre = intersect_lines(far[0], far[2], far[1], far[3])
    pose = solve_pose(far[:4], centre, BEACON, K, GRAVITY, GRAVITY_SIGMA_DEG, GravityMode.auto, 0.005)
    assert isinstance(check_fit(pose.residuals, BEACON), Refusal), "a corner 15 px off is a mismatch by default"


def test_a_rectangle_names_its_sides():
    beacon = Beacon(id=3, center_m=[0, 0, 2], yaw_deg=0, width_m=0.6, height_m=0.3, corner_radius_m=0.01)
    residuals = np.zeros(8)
    residuals[7] = 50.0  # beyond the four free parameters (the first four coordinates)
    judged = check_fit(FitResiduals(residuals, np.eye(8) * 1e-4, np.eye(8)[:, :4], 8), beacon)
    assert isinstance(judged, Refusal) and "(0.6 x 0.3 m, corner radius 0.01 m)" in judged.message
