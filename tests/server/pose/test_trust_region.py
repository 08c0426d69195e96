"""`server.pose.trust_region` is scipy's `least_squares` (TRF, a callable loss, a fixed x_scale):
the same iterates to the last bit, from starts near and far, to convergence and to the
evaluation cap; and a paused fit that goes on is the fit without the pause."""

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from server.pose.outline import _X_SCALE, _CompiledHuber, _kernels
from server.pose.trust_region import trust_region_fit
from tests.server.pose.test_outline_kernel import TRUTH, problems


def cases():
    rng = np.random.default_rng(3)
    spread = [0.05, 0.02, 0.02, 0.05, 0.05, 0.2, 0.5, 0.3, 0.3]
    for problem in problems():
        for start in [TRUTH + rng.normal(0.0, spread) for _ in range(3)]:
            yield problem, start


SIGMA = 0.2  # px, the points' noise the fits weigh them by


def evaluations(problem):
    """The residuals and the Jacobian of `problem` as functions of the parameters."""
    return (lambda p: problem.compiled_residuals(p, SIGMA)[0],
            lambda p: problem.compiled_residuals(p, SIGMA, with_jacobian=True)[1])  # fmt: skip


def fitted(problem, start, max_nfev, **pause):
    residuals, jacobian = evaluations(problem)
    return trust_region_fit(residuals, jacobian, start, residuals(start), _CompiledHuber(1.0 / SIGMA), _X_SCALE,
                            max_nfev, **pause)  # fmt: skip


@pytest.mark.parametrize("max_nfev", [60, 7])
def test_the_fit_is_least_squares_to_the_last_bit(max_nfev):
    for problem, start in cases():
        ours = fitted(problem, start, max_nfev)
        residuals, jacobian = evaluations(problem)
        theirs = least_squares(residuals, start, jac=jacobian, loss=_kernels().huber_rho, f_scale=1.0 / SIGMA,
                               x_scale=_X_SCALE, max_nfev=max_nfev)  # fmt: skip
        np.testing.assert_array_equal(ours.x, theirs.x)
        assert (ours.cost, ours.status, ours.nfev, ours.njev) == (theirs.cost, theirs.status, theirs.nfev, theirs.njev)


def test_a_paused_fit_that_goes_on_is_the_fit_without_the_pause_and_one_left_stops_there():
    for problem, start in cases():
        whole, short = fitted(problem, start, 60), fitted(problem, start, 7)
        went_on = fitted(problem, start, 60, pause_nfev=7, carry_on=lambda cost: True)
        left = fitted(problem, start, 60, pause_nfev=7, carry_on=lambda cost: False)
        np.testing.assert_array_equal(went_on.x, whole.x)
        assert (went_on.cost, went_on.status, went_on.nfev) == (whole.cost, whole.status, whole.nfev)
        np.testing.assert_array_equal(left.x, short.x)
        assert (left.cost, left.status, left.nfev) == (short.cost, short.status, short.nfev)
        assert math.isfinite(whole.cost)


def test_a_cap_that_could_never_stop_the_fit_is_refused():
    for caps in ({"max_nfev": 0}, {"max_nfev": 60, "pause_nfev": 0}):
        with pytest.raises(ValueError, match="max_nfev"):
            trust_region_fit(lambda x: x, lambda x: np.eye(1), np.ones(1), np.ones(1), None, np.ones(1), **caps)
