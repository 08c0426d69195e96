"""The compiled outline kernels are their references: the residuals and Jacobian the NumPy ones,
on random poses of one and two panels (every branch: sides, arcs, inside, the arcs frozen or not,
the priors with and without gravity and heading, a panel behind the camera); the loss scipy's
"huber", and the loss function and the scaling least_squares makes of it."""

import math
from dataclasses import replace

import numpy as np
from scipy.optimize._lsq.common import scale_for_robust_loss_function
from scipy.optimize._lsq.least_squares import construct_loss_function, huber

from server.pose.outline import BEHIND_PX, OutlineFitRules, _CompiledHuber, _problem
from server.pose.outline_kernel import huber_rho
from shared_schemas import Beacon
from tests.server.pose.test_outline import SQUARE, K, gravity, outline_points

RECTANGLE = Beacon(id=5, center_m=[0.4, 0.1, 1.1], width_m=0.6, height_m=0.2, corner_radius_m=0.03, yaw_deg=20.0)
CIRCLE = Beacon(id=6, center_m=[-0.2, 0.0, 1.0], shape="circle", diameter_m=0.2)
TRUTH = np.array([math.radians(12.0), math.radians(2.0), math.radians(-3.0), 0.03, -0.02, 0.0, 1.0, 0.2, -0.1])


def problems():
    rng = np.random.default_rng(7)
    rules = OutlineFitRules()
    noisy = [(b, outline_points(b) + rng.normal(0.0, 0.5, (len(outline_points(b)), 2))) for b in (RECTANGLE, CIRCLE)]
    yield _problem(noisy, 1.2, K, gravity(), 0.1, 10.0, None, rules)  # two panels, heading, free growth
    yield replace(_problem(noisy[:1], 1.2, K, None, 0.1, None, 1.3, rules), blur_px=1.5)  # no gravity, growth known
    square = [(SQUARE, outline_points(SQUARE) + rng.normal(0.0, 0.3, (len(outline_points(SQUARE)), 2)))]
    yield replace(_problem(square, float("nan"), K, gravity(), 0.1, None, None, rules), growth_prior_px=1.0)


def test_the_kernel_is_the_numpy_residuals_and_jacobian():
    rng = np.random.default_rng(11)
    spread = [0.05, 0.02, 0.02, 0.03, 0.03, 0.05, 0.5, 0.3, 0.3]
    for problem in problems():
        for params in [TRUTH] + [TRUTH + rng.normal(0.0, spread) for _ in range(4)]:
            for frozen in (problem, replace(problem, on_arc=problem.on_arcs(params))):
                values, jacobian = frozen.compiled_residuals(params, 0.2, with_jacobian=True)
                reference = frozen.residuals(params, 0.2)
                np.testing.assert_allclose(values, reference, rtol=1e-12, atol=1e-12 * np.abs(reference).max())
                expected = frozen.jacobian(params, 0.2)
                np.testing.assert_allclose(jacobian, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
                assert np.array_equal(frozen.compiled_residuals(params, 0.2)[0], values)


def test_a_panel_behind_the_camera_is_held_far_in_the_kernel_too():
    problem = next(problems())
    behind = TRUTH + [0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0]  # the camera above the ceiling
    values, jacobian = problem.compiled_residuals(behind, 0.2, with_jacobian=True)
    points = len(problem.rays[0])
    np.testing.assert_array_equal(values[:points], BEHIND_PX / 0.2)
    np.testing.assert_array_equal(values, problem.residuals(behind, 0.2))
    np.testing.assert_array_equal(jacobian, problem.jacobian(behind, 0.2))


def test_the_compiled_loss_is_scipys_huber():
    z = np.concatenate([np.random.default_rng(5).exponential(3.0, 1000), [0.0, 1.0, 1.0 + 1e-15, np.inf]])
    rho = np.empty((3, len(z)))
    huber(z, rho, cost_only=False)
    np.testing.assert_array_equal(huber_rho(z), rho)


def test_the_compiled_loss_function_and_scaling_are_least_squares_own():
    rng = np.random.default_rng(9)
    for f_scale in (2.0, 1 / 0.07, 1 / 0.3):
        f = rng.normal(0.0, 3.0, 600) * rng.choice([1.0, 1e-8], 600)
        expected = construct_loss_function(len(f), huber_rho, f_scale)
        loss = _CompiledHuber(f_scale)
        assert loss(f, cost_only=True) == expected(f, cost_only=True)
        rho = expected(f)
        np.testing.assert_array_equal(loss(f), rho)
        jacobian = rng.normal(size=(len(f), 9))
        scaled, scaled_f = scale_for_robust_loss_function(jacobian.copy(), f.copy(), rho)
        ours, ours_f = jacobian.copy(), f.copy()
        loss.scale(ours, ours_f, rho)
        np.testing.assert_array_equal(ours, scaled)
        np.testing.assert_array_equal(ours_f, scaled_f)
