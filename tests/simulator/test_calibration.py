"""The benchmarks' check of the reported uncertainty: the share of 2D errors inside the 95 % ellipse."""

import numpy as np
import pytest

from simulator.benchmarks import calibration, ellipse_test
from simulator.reports import Outcome, format_table, table


def gaussian_errors(seed: int, count: int, covariance_xy: np.ndarray) -> np.ndarray:
    return np.random.default_rng(seed).multivariate_normal(np.zeros(2), covariance_xy, count)


def test_gaussian_errors_fill_their_95_percent_ellipse():
    covariance = np.array([[4e-6, 1.5e-6], [1.5e-6, 1e-6]])  # a tilted, elongated ellipse (m^2)
    full = np.zeros((3, 3))
    full[:2, :2], full[2, 2] = covariance, 9e-6
    tests = [ellipse_test(d, full.tolist()) for d in gaussian_errors(0, 4000, covariance)]
    result = calibration(tests)
    assert result["ellipse95_pct"] == pytest.approx(95.0, abs=1.0)
    assert result["mean_sigma_2d_mm"] == pytest.approx(1000 * np.sqrt(5e-6))
    assert result["with_covariance"] == 4000


def test_a_covariance_claiming_too_much_or_too_little_shows():
    covariance = np.diag([1e-6, 1e-6])
    errors = gaussian_errors(1, 2000, covariance)
    bold = calibration([ellipse_test(d, (covariance / 4).tolist()) for d in errors])  # claims half the sigma
    timid = calibration([ellipse_test(d, (covariance * 4).tolist()) for d in errors])
    assert bold["ellipse95_pct"] < 60
    assert timid["ellipse95_pct"] > 99.5


def test_fixes_without_a_covariance_are_left_out():
    assert ellipse_test([0.001, 0.0], None) == (None, None)
    assert calibration([(None, None), (True, 0.001)]) == {
        "ellipse95_pct": 100.0,
        "mean_sigma_2d_mm": 1.0,
        "with_covariance": 1,
    }
    assert calibration([]) == {}


def test_grid_table_reports_the_share_of_fixes_within_the_margin():
    covariance = np.diag([1e-6, 4e-6])
    errors = gaussian_errors(2, 1000, covariance)
    outcomes = [
        Outcome(
            index=i,
            label=str(i),
            true_m=(0.0, 0.0, 0.0),
            estimate_m=(float(dx), float(dy), 0.0),
            reason=None,
            message=None,
            reprojection_px=0.01,
            covariance_xy_m2=((1e-6, 0.0), (0.0, 4e-6)),
        )
        for i, (dx, dy) in enumerate(errors)
    ]
    outcomes.append(
        Outcome(
            index=1000,
            label="far",
            true_m=(0.0, 0.0, 0.0),
            estimate_m=(0.2, 0.0, 0.0),
            reason=None,
            message=None,
            reprojection_px=0.01,
            covariance_xy_m2=((1e-6, 0), (0, 1e-6)),
        )
    )
    summary = table(outcomes)
    assert summary["outliers"] == 1 and summary["with_covariance"] == 1000  # the outlier is left out
    assert summary["ellipse95_pct"] == pytest.approx(95.0, abs=1.5)
    assert summary["mean_sigma_2d_mm"] == pytest.approx(1000 * np.sqrt(5e-6))
    assert "inside the reported 95 % ellipse" in format_table({**summary}, "test")
