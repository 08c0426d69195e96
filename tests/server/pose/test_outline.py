"""The outline fit on exact outline points (no rendering): what it must recover, and refuse."""

import math
from dataclasses import replace

import numpy as np

from server.geometry import beacon_to_world, dense_beacon_outline_m, rotation_from_ypr, world_to_camera
from server.outcomes import Refusal
from server.pose.outline import OutlineFitRules, _as_the_rule_expects, _problem, fit_outline, fit_outlines
from shared_schemas import Beacon, FailureReason

K = np.array([[978.0, 0.0, 484.5], [0.0, 978.0, 647.5], [0.0, 0.0, 1.0]])
SQUARE = Beacon(id=1, center_m=[0.0, 0.0, 1.0], side_m=0.174, corner_radius_m=0.02)
POSITION = np.array([0.03, -0.02, 0.0])
ROTATION = rotation_from_ypr(12.0, 2.0, -3.0)


def outline_points(beacon: Beacon, keep=lambda uv: np.ones(len(uv), bool)) -> np.ndarray:
    """Exact outline points (N, 2) of `beacon` seen from POSITION, ROTATION (pinhole K), filtered."""
    world = beacon_to_world(beacon, dense_beacon_outline_m(beacon, 200.0))
    camera = world_to_camera(world, POSITION, ROTATION)
    uv = (camera @ K.T)[:, :2] / camera[:, 2:]
    return uv[keep(uv)]


def gravity() -> np.ndarray:
    return ROTATION.T @ np.array([0.0, 0.0, -1.0])


def test_half_a_panel_gives_the_pose_and_a_small_covariance():
    centre_u = outline_points(SQUARE)[:, 0].mean()
    points = outline_points(SQUARE, lambda uv: uv[:, 0] < centre_u)  # the right half cut off
    fit = fit_outline(points, float("nan"), SQUARE, K, gravity(), 0.1, None)
    assert not isinstance(fit, Refusal), fit
    assert np.linalg.norm(fit.position_m - POSITION) < 2e-4
    assert 0 < fit.sigma_2d_m < 0.005


def test_two_cut_panels_together_recover_the_pose_exactly():
    # the arcs of the second panel are arcs too (a per-panel test, not "segment index >= 4")
    other = Beacon(id=2, center_m=[0.5, 0.0, 1.0], side_m=0.174, corner_radius_m=0.02)
    first = outline_points(SQUARE, lambda uv: uv[:, 1] > outline_points(SQUARE)[:, 1].mean())
    second = outline_points(other, lambda uv: uv[:, 1] < outline_points(other)[:, 1].mean())
    start = POSITION + [0.01, -0.01, 0.005]
    fit = fit_outlines([(SQUARE, first), (other, second)], float("nan"), K, gravity(), 0.1, start, 14.0, None)
    assert not isinstance(fit, Refusal), fit
    assert np.linalg.norm(fit.position_m - POSITION) < 2e-4


def test_a_sliver_of_one_side_is_refused_not_guessed():
    points = outline_points(SQUARE)
    middle = points[:, 0].mean()
    lowest = points[:, 1].max()
    sliver = points[(np.abs(points[:, 0] - middle) < 20) & (points[:, 1] > lowest - 3)]
    refusal = fit_outline(sliver, float("nan"), SQUARE, K, gravity(), 0.1, None)
    assert isinstance(refusal, Refusal) and refusal.reason is FailureReason.beacon_cut_off


def test_a_circle_needs_a_heading():
    circle = Beacon(id=3, center_m=[0.0, 0.0, 1.0], shape="circle", diameter_m=0.2)
    refusal = fit_outline(outline_points(circle), float("nan"), circle, K, gravity(), 0.1, None)
    assert isinstance(refusal, Refusal) and "heading_deg" in refusal.message


def test_the_rule_turns_a_rectangle_pose_by_half_a_turn_about_its_centre():
    rectangle = Beacon(id=4, center_m=[1.0, 2.0, 3.0], width_m=1.2, height_m=0.3, corner_radius_m=0.01)
    # camera yaw 150 degrees from the beacon's: the rule (within 90) wants the copy at -30
    params = np.array([math.radians(150.0), 0.01, -0.02, 1.3, 2.1, 1.6, 1.0, 0.0, 0.0])
    turned = _as_the_rule_expects(params, rectangle, None)
    assert math.isclose(math.degrees(turned[0]), -30.0, abs_tol=1e-9)
    np.testing.assert_allclose(turned[3:5], [0.7, 1.9])  # mirrored through the point under the centre
    np.testing.assert_array_equal(turned[[1, 2, 5, 6]], params[[1, 2, 5, 6]])


def test_the_analytic_jacobian_is_the_central_differences():
    # two panels, a rounded rectangle and a circle, points off the outline, the blur's arc term on:
    # every branch of the signed distance (sides, arcs, inside) and of the growth's terms
    rectangle = Beacon(id=5, center_m=[0.4, 0.1, 1.1], width_m=0.6, height_m=0.2, corner_radius_m=0.03, yaw_deg=20.0)
    circle = Beacon(id=6, center_m=[-0.2, 0.0, 1.0], shape="circle", diameter_m=0.2)
    rng = np.random.default_rng(3)
    panels = [(b, outline_points(b) + rng.normal(0.0, 0.5, (len(outline_points(b)), 2))) for b in (rectangle, circle)]
    problem = _problem(panels, 1.2, K, gravity(), 0.1, 10.0, None, OutlineFitRules())
    problem = replace(problem, growth_prior_px=1.0, blur_px=1.5)
    truth = np.array([math.radians(12.0), math.radians(2.0), math.radians(-3.0), *POSITION, 1.0, 0.2, -0.1])
    for params in (truth, truth + [0.02, -0.01, 0.01, 0.01, -0.02, 0.03, 0.5, 0.3, 0.2]):
        for frozen in (problem, replace(problem, on_arc=problem.on_arcs(params))):
            numeric = frozen.numeric_jacobian(params, 0.1)
            np.testing.assert_allclose(frozen.jacobian(params, 0.1), numeric, rtol=0, atol=1e-6 * np.abs(numeric).max())
