"""Which distortion terms the fit keeps: the F-test against lenses with and without k3 and the tangential pair.

The views are the board's corners projected through the lens with Gaussian noise (no rendering): the
test is of the statistics, not of finding corners.
"""

import numpy as np
import pytest

from server.calibration.board import charuco_board
from server.calibration.fit import PARAMETERS, FitRules, drop_test_p, fit_views
from server.calibration.lens import Lens, distortion_difference_px
from shared_schemas.calibration import BoardView
from simulator.board import PoseSet, board_poses
from tests.calibration_photos import BOARD, HEIGHT, LENS, RULES, WIDTH

NOISE_PX = 0.03  # a rendered photo's corners are off by ~0.02-0.05 px
# the tests' lens with a decentring a phone may have (~1 px at the frame's corners), clear of the noise
TILTED = Lens(LENS.fx, LENS.fy, LENS.cx, LENS.cy, (0.06, -0.03, 2e-3, -1.5e-3, 0.0))


def _views(lens: Lens, seed: int, count: int = 15) -> list[BoardView]:
    rng = np.random.default_rng(seed)
    corners = np.asarray(charuco_board(BOARD).getChessboardCorners(), float)
    views = []
    for k, pose in enumerate(board_poses(BOARD, lens, WIDTH, HEIGHT, count, rng, PoseSet.good, RULES)):
        pixels = lens.project(corners @ pose.rotation.T + pose.translation) + rng.normal(0, NOISE_PX, (len(corners), 2))
        inside = np.flatnonzero((pixels >= 0).all(axis=1) & (pixels[:, 0] <= WIDTH - 1) & (pixels[:, 1] <= HEIGHT - 1))
        views.append(
            BoardView(
                name=f"v{k}", width=WIDTH, height=HEIGHT, corner_ids=inside.tolist(), corners_px=pixels[inside].tolist()
            )
        )
    return views


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_lens_without_k3_gets_k3_fixed_at_zero(seed):
    fit = fit_views(_views(TILTED, seed), BOARD)
    assert fit.fixed == ("k3",) and fit.lens.distortion[4] == 0
    # a fixed term is no parameter: no variance, no correlation
    assert np.all(fit.covariance[8] == 0) and np.all(fit.covariance[:, 8] == 0)
    assert np.all(np.diag(fit.covariance)[:8] > 0) and fit.covariance.shape == (PARAMETERS, PARAMETERS)
    assert dict(fit.term_p_values)["k3"] > 1e-3 and dict(fit.term_p_values)["p1+p2"] < 1e-3


def test_a_lens_with_k3_keeps_it():
    # k3 0.03 moves the frame's corners (normalised radius ~0.7) by ~1.4 px
    lens = Lens(TILTED.fx, TILTED.fy, TILTED.cx, TILTED.cy, (*TILTED.distortion[:4], 0.03))
    fit = fit_views(_views(lens, 1), BOARD)
    assert fit.fixed == () and dict(fit.term_p_values)["k3"] < 1e-3
    assert abs(fit.lens.distortion[4] - 0.03) < 4 * np.sqrt(fit.covariance[8, 8])
    # dropping it regardless (every p-value is above 0) would bend the frame's corners
    dropped = fit_views(_views(lens, 1), BOARD, FitRules(significance=0.0))
    assert dropped.fixed == ("k3", "p1", "p2")
    kept_error = distortion_difference_px(lens, fit.lens, WIDTH, HEIGHT)
    assert distortion_difference_px(lens, dropped.lens, WIDTH, HEIGHT) > 3 * kept_error, kept_error


def test_a_lens_without_tangential_terms_gets_them_fixed():
    lens = Lens(LENS.fx, LENS.fy, LENS.cx, LENS.cy, (*LENS.distortion[:2], 0.0, 0.0, 0.0))
    fit = fit_views(_views(lens, 2), BOARD)
    assert fit.fixed == ("k3", "p1", "p2") and fit.lens.distortion[2:] == (0.0, 0.0, 0.0)
    assert distortion_difference_px(lens, fit.lens, WIDTH, HEIGHT) < 0.1


def test_no_term_is_tested_when_none_is_optional():
    fit = fit_views(_views(TILTED, 1), BOARD, FitRules(optional_terms=()))
    assert fit.fixed == () and fit.term_p_values == () and np.all(np.diag(fit.covariance) > 0)


def test_the_drop_test():
    # no rise of the residuals: nothing explained, the terms go; a rise of 30 residual variances for one term: kept
    assert drop_test_p(100.0, 100.0, 1, 1000) == pytest.approx(1.0)
    assert drop_test_p(103.0, 100.0, 1, 1000) < 1e-6
    # F(1, dof) at 3.84 is the 5 % level for a large dof
    assert drop_test_p(100.0 + 3.84 * 0.1, 100.0, 1, 1000) == pytest.approx(0.05, abs=0.002)
    assert drop_test_p(0.0, 0.0, 2, 10) == 1.0
