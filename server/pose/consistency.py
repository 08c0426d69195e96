"""Stage 9: does the fitted panel explain the frame within the noise the fit itself measured?

A pose always fits: given any four corners and a map beacon, the solver returns the view of the
beacon nearest to them. Whether that view explains what the frame shows is a separate question,
asked here of every fix of the corner path: the residuals the fit left (the four corners against
the map beacon's projected corners, and the tilt against the gravity sensor when the frame has
one) are compared with the noise that frame's own sides measured (`solve.corner_covariance`: the
sides' scatter and slow wave, their pixel-locking at the frame's blur, the clipped-edge growth's
error and its spread over the corners) and the sensor's sigma, as a chi-square. The paper's own
paths (`--no-subpixel`) measure no noise of their own and are not tested.

The chi-square is the generalised least-squares one, r^T (S^-1 - S^-1 J (J^T S^-1 J)^-1 J^T S^-1) r
(r residuals, S their covariance, J their Jacobian in the fit's free parameters): the smallest
weighted residual any pose near the fit leaves, so it does not depend on which pose near the
fit the solver stopped at, nor on the weights it used. Under the noise model it follows a
chi-square distribution with (residuals - free parameters) degrees of freedom: 8 corner
coordinates + 2 tilt components - 6 pose parameters = 4 with a gravity sensor (whether the fit
weighed its tilt or took it as it is: it is a measurement with its own error either way), 8 - 6 = 2
without. The centre, cut from the corners' diagonals, is no measurement of its own and is not
counted.

A wrong map (corner radius, size against the corner radius, the wrong beacon of a room) moves
the corners by pixels to hundreds of pixels where their noise is hundredths: a chi-square of
thousands to millions. A wrong `side_m` alone, the shape kept, only scales the distance: every
view of the scaled panel explains the frame as well, and no test of one frame can see it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.special import chdtrc, chdtri

from server.outcomes import Refusal
from shared_schemas import Beacon, FailureReason


@dataclass(frozen=True)
class ConsistencyRules:
    # A fix is refused when residuals as large as its own come by chance less often than this under
    # the noise its frame measured: one good fix in a million, were the noise model exact. The wrong
    # maps this test is for give p-values below 1e-100; the margin covers what the noise model knows
    # only roughly (a chi-square per degree of freedom of 8 passes at 4 degrees of freedom).
    min_p_value: float = 1e-6
    # ... and when the corners sit farther than this from the fitted panel (rms): what the noise model
    # does not hold yet moves good corners by up to 1-1.7 px (a moving camera's readout skew, walking at
    # 1 m/s; a brightness gradient over the panel: 0.06-0.3 px on bench-real and tilt frames), which the
    # chi-square alone refused on 88 % of walking frames and 10-12 % of still ones. The wrong maps it is
    # for sit 100-250 px off; this floor goes when the model has the skew (docs/reliability.md).
    min_rms_px: float = 2.0
    check: bool = True


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class FitResiduals:
    """What a fit left unexplained, with the noise it measured.

    residuals (n,): measurements minus the fitted model's prediction, the `pixel_terms` first in
    undistorted pixels (x0 y0 x1 y1 ... of the corners), then any others (the tilt against the
    gravity sensor, rad); covariance (n, n): their noise, in the same units; jacobian (n, k): the
    residuals' derivatives in the fit's k free parameters at the fit.
    """

    residuals: np.ndarray
    covariance: np.ndarray
    jacobian: np.ndarray
    pixel_terms: int

    @property
    def pixel_rms_px(self) -> float:
        """RMS distance of the measured points from the fitted model's (px)."""
        pixels = self.residuals[: self.pixel_terms].reshape(-1, 2)
        return float(np.sqrt(np.mean(np.sum(pixels**2, axis=1))))


@dataclass(frozen=True)
class Consistency:
    chi_square: float
    dof: int
    p_value: float  # chance of a chi-square this large or larger under the noise model
    pixel_rms_px: float


def chi_square(residuals: np.ndarray, covariance: np.ndarray, jacobian: np.ndarray) -> tuple[float, int]:
    """(generalised least-squares chi-square, degrees of freedom) of `residuals` (n,) with
    `covariance` (n, n) after the best step in the parameters of `jacobian` (n, k).

    (nan, 0) when the covariance is not positive definite or the parameters are degenerate.
    """
    both = np.empty((len(residuals), 1 + jacobian.shape[1]))  # np.column_stack's, in one call less
    both[:, 0], both[:, 1:] = residuals, jacobian
    ok, solved = cv2.solve(covariance, both, flags=cv2.DECOMP_CHOLESKY)
    if not ok:
        return math.nan, 0
    b = jacobian.T @ solved[:, 0]
    ok, step = cv2.solve(jacobian.T @ solved[:, 1:], b, flags=cv2.DECOMP_CHOLESKY)
    if not ok:
        return math.nan, 0
    return float(residuals @ solved[:, 0] - b @ step.ravel()), len(residuals) - jacobian.shape[1]


def consistency(fit: FitResiduals) -> Consistency:
    """The fit's chi-square against its own noise, and how likely it is (`chi_square`)."""
    value, dof = chi_square(fit.residuals, fit.covariance, fit.jacobian)
    p_value = float(chdtrc(dof, value)) if dof > 0 and math.isfinite(value) else 1.0
    return Consistency(value, dof, p_value, fit.pixel_rms_px)


def check_fit(fit: FitResiduals, beacon: Beacon, rules: ConsistencyRules = ConsistencyRules()) -> Consistency | Refusal:
    """The fit's `Consistency`, or a `shape_mismatch` refusal when the map beacon `beacon` does not
    explain the corners within their measured noise (p below `rules.min_p_value`) and they sit more
    than `rules.min_rms_px` from its best view.

    A fit whose chi-square cannot be computed (a degenerate noise model) passes: that is not
    evidence against the map, and the covariance stage says what it can of such a fix.
    """
    found = consistency(fit)
    if not rules.check or found.p_value >= rules.min_p_value or found.pixel_rms_px <= rules.min_rms_px:
        return found
    limit = float(chdtri(found.dof, rules.min_p_value))
    width, height = beacon.extent_m
    size = f"{width:g} m" if width == height else f"{width:g} x {height:g} m"
    return Refusal(
        FailureReason.shape_mismatch,
        f"the panel's corners sit {found.pixel_rms_px:.3g} px (rms) from map beacon {beacon.id}'s shape "
        f"({size}, corner radius {beacon.corner_radius_m:g} m) in the best view of it: chi-square "
        f"{found.chi_square:.3g} for {found.dof} degrees of freedom against the noise its sides measured, "
        f"{limit:.3g} allowed (p {rules.min_p_value:g}; {rules.min_rms_px:g} px): is its corner radius or size "
        f"right, and is it the beacon in view?",
    )
