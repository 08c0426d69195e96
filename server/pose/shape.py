"""Is the blob the outline fit fitted the map's panel? The fit judged as a shape test (beyond the paper).

The outline fit (`server.pose.outline`) finds the pose that brings a panel's outline closest to
the visible edge points; a lamp, a window, a louvred troffer, a reflection or two lights merged
get a pose as well, and only the fit's sigma stood between them and a fix. Here the fit is held
to what a panel of the map's shape would leave:

- the residuals are the edge noise: the points' distances to the fitted outline against the
  noise measured on the edge itself without any model (`server.vision.outline.run_scatter_px`:
  each point about its neighbours' chord along short runs), plus pixel locking, which the run
  scatter cannot see (it changes slowly along an edge): a level crossing interpolated between
  pixels is off by up to ~0.1 px with the edge's sub-pixel phase (docs/accuracy.md), taken whole
  as `locking_px` RMS. chi^2 = sum r^2 / sigma^2 over the explained points; neighbours nearer than
  `independent_px` read the same pixels, so the sum counts one point per `independent_px` of
  outline and so do the degrees of freedom (less the fit's 9 parameters: pose, growth and its
  gradient), refused beyond the chi-square's quantile at `false_alarm`;
- the share of the points the model explains (within `explained_sigmas` of the outline), which
  the chi-square over the explained points cannot see: a blob whose outline the model follows
  only in part (a lamp's round end, a troffer's louvres, a second light merged);
- the share of the model's outline that lies in the frame and has edge points along it: the
  straight runs and arcs the map's shape would show, which a cut-off blob fitted as a larger
  panel leaves out (a troffer or a window cut by the frame, fitted as a panel whose other sides
  should be in view).

All three are refused as `shape_mismatch`, whatever the map's `required_sigma_m` says, with a
message naming what did not match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import chi2 as chi2_distribution

from server.outcomes import Refusal
from shared_schemas import Beacon, FailureReason


@dataclass(frozen=True)
class ShapeRules:
    # the chance that a panel's own residuals fail the chi-square: one frame in a million
    false_alarm: float = 1e-6
    # a sub-pixel crossing's error the run scatter cannot see: pixel locking, up to 0.1 px with the
    # edge's phase, taken whole (it also stands for the fit's own approximations of the same size:
    # one growth and its gradient for the whole outline, the blur's rounding of the arcs; a device
    # session's cut panels, whose growth is held to their complete ones', leave 0.10 px RMS)
    locking_px: float = 0.1
    # a crossing is interpolated from the pixels within about a pixel of its profile: points
    # nearer than this share pixels and their errors
    independent_px: float = 2.0
    noise_floor_px: float = 0.02  # what one frame cannot show (`OutlineFitRules.point_sigma_floor_px`)
    explained_sigmas: float = 4.0  # a point this many of its sigmas from the outline is not explained
    # share of the points the model must explain: a panel's residuals are its edge noise, beyond 4
    # sigma 6e-5 of them; the rest is room for what lies on its outline but is not its edge (a
    # sprinkler, a cable, a neighbour's light)
    min_explained: float = 0.97
    # the model's outline in view is covered where an edge point lies within this (px) of it, beyond
    # the fitted growth (the points lie D px outside the outline) and the points' own spacing
    cover_px: float = 3.0
    min_covered: float = 0.8  # share of the model's outline in view that must have edge points


@dataclass(frozen=True)
class ShapeTest:
    """The evidence of one outline fit against its panel's shape."""

    chi2: float
    dof: int
    limit: float  # the chi-square's quantile at `ShapeRules.false_alarm`
    rms_px: float  # of the explained points' residuals
    noise_px: float  # one point's expected error (the measured edge noise)
    explained: float  # share of the points within `explained_sigmas`
    covered: float | None  # share of the model's outline in view with points along it; None: none in view


def _shape_name(beacon: Beacon) -> str:
    if not beacon.has_corners:
        return "circle"
    width, height = beacon.extent_m
    return "rounded square" if math.isclose(width, height) else "rounded rectangle"


def covered_share(model_px: np.ndarray, points_px: np.ndarray, tolerance_px: float) -> float | None:
    """The share of model outline samples (M, 2) with an edge point (N, 2) within `tolerance_px`."""
    if len(model_px) == 0:
        return None
    # The k-d tree takes finite points only: a non-finite edge point meets no sample, a non-finite
    # sample is not covered (as with the distance matrix before it).
    points_px, finite = points_px[np.isfinite(points_px).all(axis=1)], np.isfinite(model_px).all(axis=1)
    if len(points_px) == 0 or not finite.any():
        return 0.0
    gap, _ = cKDTree(points_px).query(model_px[finite])  # each sample's nearest edge point (no M x N distances)
    return float(np.count_nonzero(gap <= tolerance_px) / len(model_px))


def shape_test(
    residuals_px: np.ndarray,
    parameters: int,
    edge_noise_px: float,
    model_in_view_px: np.ndarray,
    points_px: np.ndarray,
    growth_px: float = 0.0,
    rules: ShapeRules = ShapeRules(),
) -> ShapeTest:
    """The evidence: residuals (N,) of the fit, its free `parameters`, the
    edge noise (px, NaN: unmeasured, the floor taken), the model's outline samples that lie in
    view (M, 2) and the edge points (N, 2), both in frame pixels, and the fit's growth (px)."""
    noise = max(edge_noise_px if math.isfinite(edge_noise_px) else 0.0, rules.noise_floor_px)
    sigma = math.hypot(noise, rules.locking_px)  # one point's whole expected error
    explained = np.abs(residuals_px) <= rules.explained_sigmas * sigma
    spacing = float(np.median(np.linalg.norm(np.diff(points_px, axis=0), axis=1))) if len(points_px) > 1 else 1.0
    per_point = min(1.0, spacing / rules.independent_px)  # independent points per point
    dof = max(round(explained.sum() * per_point) - parameters, 1)
    chi2 = float(np.sum((residuals_px[explained] / sigma) ** 2)) * per_point
    return ShapeTest(
        chi2=chi2,
        dof=dof,
        limit=float(chi2_distribution.isf(rules.false_alarm, dof)),
        rms_px=float(np.sqrt(np.mean(residuals_px[explained] ** 2))) if explained.any() else math.inf,
        noise_px=sigma,
        explained=float(explained.mean()) if len(explained) else 0.0,
        covered=covered_share(model_in_view_px, points_px, rules.cover_px + abs(growth_px) + spacing),
    )


def shape_refusal(test: ShapeTest, beacon: Beacon, rules: ShapeRules = ShapeRules()) -> Refusal | None:
    """`shape_mismatch` naming what did not match, or None when the blob is the panel's shape."""
    shape = f"map beacon {beacon.id}'s {_shape_name(beacon)}"
    if test.explained < rules.min_explained:
        message = (
            f"only {test.explained:.0%} of the visible outline's points lie within {rules.explained_sigmas:g} sigma "
            f"({rules.explained_sigmas * test.noise_px:.2f} px) of {shape}: not this panel?"
        )
    elif test.chi2 > test.limit:
        message = (
            f"the visible outline's points sit {test.rms_px:.2f} px RMS from {shape}, {test.noise_px:.2f} px "
            f"expected from the edge noise (chi-square {test.chi2:.0f} for {test.dof} degrees of freedom, "
            f"at most {test.limit:.0f}): not this panel?"
        )
    elif test.covered is not None and test.covered < rules.min_covered:
        message = (
            f"only {test.covered:.0%} of the outline {shape} would show in the frame has edges along it: "
            f"not this panel?"
        )
    else:
        return None
    return Refusal(FailureReason.shape_mismatch, message)
