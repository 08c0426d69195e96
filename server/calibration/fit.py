"""The calibration fit: pinhole and distortion from board views, with their covariance.

OpenCV's `calibrateCameraExtended` (Zhang's method, then Levenberg-Marquardt over fx, fy, cx,
cy, k1, k2, p1, p2, k3 and each view's pose) minimises the corners' reprojection error. Misread
corners are outliers of that fit: corners further than `FitRules.outlier_sigmas` robust sigmas
from their reprojection are dropped and the fit repeated. The covariance is the Gauss-Newton one
at the solution, sigma^2 (J^T J)^-1 with J over every parameter (views' poses included, so the
intrinsics' uncertainty carries their correlation with the poses) and sigma^2 the residuals'
variance; its diagonal is OpenCV's own standard deviations.

Which distortion terms the views support is decided by evidence, as phone calibrations commonly
do: k3 (the r^6 term) and the tangential pair (p1, p2) are each fitted and kept only when they
lower the residuals significantly (a nested-model F-test on the kept corners, `FitRules`);
otherwise the term is fixed at 0 (the contract's five coefficients stay, with 0 for an unsupported
term). An unsupported k3 is free to bend the far corners of the frame, where few corners pin it:
with 20 views it took the distortion at the frame's corners 0.1 px off a lens with k3 = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy import stats

from server.calibration.board import corner_points_m
from server.calibration.lens import Lens
from shared_schemas.calibration import BoardSpec, BoardView

PARAMETERS = 9  # fx, fy, cx, cy, k1, k2, p1, p2, k3
POSE_PARAMETERS = 6  # rvec, tvec of each view
# the OpenCV flag that fixes each optional group at 0, and the group's columns among the 9 parameters
_TERM_FLAGS = {("k3",): cv2.CALIB_FIX_K3, ("p1", "p2"): cv2.CALIB_ZERO_TANGENT_DIST}
_TERM_COLUMNS = {"p1": 6, "p2": 7, "k3": 8}


@dataclass(frozen=True)
class FitRules:
    # a residual this many robust sigmas (median residual length / 1.1774, a 2-D Gaussian's median) out is
    # a misread corner, not noise: a Gaussian gives one in ~70 million
    outlier_sigmas: float = 6.0
    min_outlier_px: float = 0.3  # below this every corner is good enough: no dropping on a perfect fit
    passes: int = 3
    max_iterations: int = 100
    # distortion terms kept only when the views support them, tried in this order: each group is dropped (fixed
    # at 0) unless dropping it makes the fit worse at this significance (nested-model F-test); k3 first, as the
    # highest power of the radius is the first to fit noise at the frame's corners
    optional_terms: tuple[tuple[str, ...], ...] = (("k3",), ("p1", "p2"))
    significance: float = 1e-3


@dataclass(frozen=True)
class ViewPose:
    rotation: np.ndarray  # (3, 3) board to camera
    translation: np.ndarray  # (3,) metres
    residuals_px: np.ndarray  # (N, 2) measured - reprojected, of the view's kept corners
    kept: np.ndarray  # (corners of the view,) bool: not an outlier


@dataclass(frozen=True)
class Fit:
    lens: Lens
    rms_px: float
    covariance: np.ndarray  # (9, 9) of fx, fy, cx, cy, k1, k2, p1, p2, k3
    opencv_sigmas: np.ndarray  # (9,) OpenCV's standard deviations of the same
    poses: list[ViewPose]
    dropped: int  # outlier corners
    fixed: tuple[str, ...] = ()  # distortion terms the views did not support, fixed at 0
    term_p_values: tuple[tuple[str, float], ...] = ()  # each tested group's F-test p-value (small: kept)


def _normal_matrix(lens: Lens, objects: list[np.ndarray], rvecs, tvecs, masks: list[np.ndarray]) -> np.ndarray:
    """J^T J over the intrinsics (first 9) and each view's pose (6 each), built view by view.

    J (2 rows per corner) is never held whole: 200 views of 4000 corners would make it 15 GB.
    """
    size = PARAMETERS + POSE_PARAMETERS * len(objects)
    normal = np.zeros((size, size))
    for k, (points, rvec, tvec, mask) in enumerate(zip(objects, rvecs, tvecs, masks, strict=True)):
        _, local = cv2.projectPoints(points[mask], rvec, tvec, lens.matrix, lens.coefficients)
        # OpenCV's columns: rvec 3, tvec 3, fx fy, cx cy, distortion 5
        intrinsic, pose = local[:, 6 : 6 + PARAMETERS], local[:, :POSE_PARAMETERS]
        column = PARAMETERS + POSE_PARAMETERS * k
        normal[:PARAMETERS, :PARAMETERS] += intrinsic.T @ intrinsic
        normal[:PARAMETERS, column : column + POSE_PARAMETERS] = intrinsic.T @ pose
        normal[column : column + POSE_PARAMETERS, :PARAMETERS] = pose.T @ intrinsic
        normal[column : column + POSE_PARAMETERS, column : column + POSE_PARAMETERS] = pose.T @ pose
    return normal


def _calibrate(objects, images, size, rules: FitRules, flags: int):
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, rules.max_iterations, 1e-12)
    # the initial matrix and coefficients are placeholders: without CALIB_USE_INTRINSIC_GUESS OpenCV starts from Zhang
    return cv2.calibrateCameraExtended(objects, images, size, np.eye(3), np.zeros(5), flags=flags, criteria=criteria)


@dataclass(frozen=True)
class _Solution:
    lens: Lens
    rvecs: tuple
    tvecs: tuple
    sigmas: np.ndarray
    errors: list[np.ndarray]  # (corners of the view,) reprojection error of every corner, kept or not
    residual_sum: float  # sum of squared residuals of the kept corners (px^2)


def _solve(objects, measured, masks, size, rules: FitRules, flags: int) -> _Solution:
    """One OpenCV fit of the kept corners, and every corner's reprojection error under it."""
    _, matrix, distortion, rvecs, tvecs, sigmas, _, _ = _calibrate(
        [o[m] for o, m in zip(objects, masks, strict=True)],
        [p[m] for p, m in zip(measured, masks, strict=True)],
        size,
        rules,
        flags,
    )
    lens = Lens(matrix[0, 0], matrix[1, 1], matrix[0, 2], matrix[1, 2], tuple(distortion.ravel()[:5].tolist()))
    errors = [
        np.linalg.norm(cv2.projectPoints(o, r, t, lens.matrix, lens.coefficients)[0].reshape(-1, 2) - p, axis=1)
        for o, p, r, t in zip(objects, measured, rvecs, tvecs, strict=True)
    ]
    residual_sum = float(sum(np.sum(e[m] ** 2) for e, m in zip(errors, masks, strict=True)))
    return _Solution(lens, rvecs, tvecs, np.asarray(sigmas, float).ravel()[:PARAMETERS], errors, residual_sum)


def _outlier_masks(objects, measured, size, rules: FitRules) -> list[np.ndarray]:
    """The corners to keep: misread ones dropped under the full model, the fit repeated until none changes."""
    masks = [np.ones(len(points), bool) for points in objects]
    for _ in range(rules.passes):
        solution = _solve(objects, measured, masks, size, rules, 0)
        kept = np.concatenate([e[m] for e, m in zip(solution.errors, masks, strict=True)])
        limit = max(rules.min_outlier_px, rules.outlier_sigmas * float(np.median(kept)) / 1.1774)
        new_masks = [mask & (e <= limit) for e, mask in zip(solution.errors, masks, strict=True)]
        # a view needs four corners for its pose; never drop below that
        new_masks = [new if new.sum() >= 4 else old for new, old in zip(new_masks, masks, strict=True)]
        if all(np.array_equal(a, b) for a, b in zip(new_masks, masks, strict=True)):
            break
        masks = new_masks
    return masks


def drop_test_p(reduced_sum: float, full_sum: float, dropped: int, dof: int) -> float:
    """The nested-model F-test's p-value of dropping `dropped` parameters from a fit with `dof` degrees of freedom.

    Under the hypothesis that the dropped terms are 0 (and Gaussian corner noise), the rise of the
    residual sum per dropped parameter over the full fit's residual variance is F(dropped, dof):
    a small p-value means the terms explain real structure and stay.
    """
    if full_sum <= 0:
        return 0.0 if reduced_sum > 0 else 1.0
    f = max(0.0, reduced_sum - full_sum) / dropped / (full_sum / dof)
    return float(stats.f.sf(f, dropped, dof))


def _select_terms(
    objects, measured, masks, size, rules: FitRules
) -> tuple[_Solution, tuple[str, ...], tuple[tuple[str, float], ...]]:
    """The fit with only the optional distortion terms the views support; the terms fixed at 0 and each p-value."""
    observations = 2 * int(sum(m.sum() for m in masks))
    flags, p_values = 0, []
    fixed: tuple[str, ...] = ()
    solution = _solve(objects, measured, masks, size, rules, flags)
    for group in rules.optional_terms:
        parameters = PARAMETERS - len(fixed) + POSE_PARAMETERS * len(objects)
        reduced = _solve(objects, measured, masks, size, rules, flags | _TERM_FLAGS[group])
        p = drop_test_p(reduced.residual_sum, solution.residual_sum, len(group), max(1, observations - parameters))
        p_values.append(("+".join(group), p))
        if p > rules.significance:
            flags, solution, fixed = flags | _TERM_FLAGS[group], reduced, fixed + group
    return solution, fixed, tuple(p_values)


def fit_views(views: list[BoardView], spec: BoardSpec, rules: FitRules = FitRules()) -> Fit:
    """Fit the lens to views of one size (at least 3, each with 4 or more corners); raises cv2.error if OpenCV fails."""
    size = (views[0].width, views[0].height)
    objects = [corner_points_m(spec, view.corner_ids).astype(np.float32) for view in views]
    measured = [np.asarray(view.corners_px, np.float32) for view in views]
    masks = _outlier_masks(objects, measured, size, rules)
    solution, fixed, p_values = _select_terms(objects, measured, masks, size, rules)
    lens = solution.lens
    objects64 = [o.astype(float) for o in objects]
    poses, residuals = [], []
    for o, m, r, t, mask in zip(objects64, measured, solution.rvecs, solution.tvecs, masks, strict=True):
        reprojected = cv2.projectPoints(o[mask], r, t, lens.matrix, lens.coefficients)[0].reshape(-1, 2)
        residuals.append(m[mask] - reprojected)
        poses.append(ViewPose(cv2.Rodrigues(r)[0], np.asarray(t, float).ravel(), residuals[-1], mask))
    stacked = np.concatenate(residuals)
    normal = _normal_matrix(lens, objects64, solution.rvecs, solution.tvecs, masks)
    # a fixed term is no parameter: its row and column leave the normal matrix, its covariance is 0
    free = np.setdiff1d(np.arange(normal.shape[0]), [_TERM_COLUMNS[name] for name in fixed]).astype(int)
    dof = max(1, stacked.size - free.size)
    variance = float(np.sum(stacked**2)) / dof
    covariance = np.zeros((PARAMETERS, PARAMETERS))
    intrinsic = free[free < PARAMETERS]
    covariance[np.ix_(intrinsic, intrinsic)] = (
        np.linalg.pinv(normal[np.ix_(free, free)])[: intrinsic.size, : intrinsic.size] * variance
    )
    return Fit(
        lens=lens,
        rms_px=float(np.sqrt(np.mean(np.sum(stacked**2, axis=1)))),
        covariance=covariance,
        opencv_sigmas=solution.sigmas,
        poses=poses,
        dropped=int(sum((~m).sum() for m in masks)),
        fixed=fixed,
        term_p_values=p_values,
    )
