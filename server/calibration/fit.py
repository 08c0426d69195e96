"""The calibration fit: pinhole and distortion from board views, with their covariance.

OpenCV's `calibrateCameraExtended` (Zhang's method, then Levenberg-Marquardt over fx, fy, cx,
cy, k1, k2, p1, p2, k3 and each view's pose) minimises the corners' reprojection error. Misread
corners are outliers of that fit: corners further than `FitRules.outlier_sigmas` robust sigmas
from their reprojection are dropped and the fit repeated. The covariance is the Gauss-Newton one
at the solution, sigma^2 (J^T J)^-1 with J over every parameter (views' poses included, so the
intrinsics' uncertainty carries their correlation with the poses) and sigma^2 the residuals'
variance; its diagonal is OpenCV's own standard deviations.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.calibration.board import corner_points_m
from server.calibration.lens import Lens
from shared_schemas.calibration import BoardSpec, BoardView

PARAMETERS = 9  # fx, fy, cx, cy, k1, k2, p1, p2, k3
POSE_PARAMETERS = 6  # rvec, tvec of each view


@dataclass(frozen=True)
class FitRules:
    # a residual this many robust sigmas (median residual length / 1.1774, a 2-D Gaussian's median) out is
    # a misread corner, not noise: a Gaussian gives one in ~70 million
    outlier_sigmas: float = 6.0
    min_outlier_px: float = 0.3  # below this every corner is good enough: no dropping on a perfect fit
    passes: int = 3
    max_iterations: int = 100


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


def _calibrate(objects, images, size, rules: FitRules):
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, rules.max_iterations, 1e-12)
    # the initial matrix and coefficients are placeholders: without CALIB_USE_INTRINSIC_GUESS OpenCV starts from Zhang
    return cv2.calibrateCameraExtended(objects, images, size, np.eye(3), np.zeros(5), criteria=criteria)


def fit_views(views: list[BoardView], spec: BoardSpec, rules: FitRules = FitRules()) -> Fit:
    """Fit the lens to views of one size (at least 3, each with 4 or more corners); raises cv2.error if OpenCV fails."""
    size = (views[0].width, views[0].height)
    objects = [corner_points_m(spec, view.corner_ids).astype(np.float32) for view in views]
    measured = [np.asarray(view.corners_px, np.float32) for view in views]
    masks = [np.ones(len(points), bool) for points in objects]
    for _ in range(rules.passes):
        _, matrix, distortion, rvecs, tvecs, sigmas, _, _ = _calibrate(
            [o[m] for o, m in zip(objects, masks, strict=True)],
            [p[m] for p, m in zip(measured, masks, strict=True)],
            size,
            rules,
        )
        lens = Lens(matrix[0, 0], matrix[1, 1], matrix[0, 2], matrix[1, 2], tuple(distortion.ravel()[:5].tolist()))
        errors = [
            np.linalg.norm(cv2.projectPoints(o, r, t, lens.matrix, lens.coefficients)[0].reshape(-1, 2) - p, axis=1)
            for o, p, r, t in zip(objects, measured, rvecs, tvecs, strict=True)
        ]
        kept = np.concatenate([e[m] for e, m in zip(errors, masks, strict=True)])
        limit = max(rules.min_outlier_px, rules.outlier_sigmas * float(np.median(kept)) / 1.1774)
        new_masks = [mask & (e <= limit) for e, mask in zip(errors, masks, strict=True)]
        # a view needs four corners for its pose; never drop below that
        new_masks = [new if new.sum() >= 4 else old for new, old in zip(new_masks, masks, strict=True)]
        if all(np.array_equal(a, b) for a, b in zip(new_masks, masks, strict=True)):
            break
        masks = new_masks
    objects64 = [o.astype(float) for o in objects]
    poses, residuals = [], []
    for o, p, r, t, mask in zip(objects64, measured, rvecs, tvecs, masks, strict=True):
        reprojected = cv2.projectPoints(o[mask], r, t, lens.matrix, lens.coefficients)[0].reshape(-1, 2)
        residuals.append(p[mask] - reprojected)
        poses.append(ViewPose(cv2.Rodrigues(r)[0], np.asarray(t, float).ravel(), residuals[-1], mask))
    stacked = np.concatenate(residuals)
    normal = _normal_matrix(lens, objects64, rvecs, tvecs, masks)
    dof = max(1, stacked.size - normal.shape[0])
    variance = float(np.sum(stacked**2)) / dof
    covariance = np.linalg.pinv(normal)[:PARAMETERS, :PARAMETERS] * variance
    return Fit(
        lens=lens,
        rms_px=float(np.sqrt(np.mean(np.sum(stacked**2, axis=1)))),
        covariance=covariance,
        opencv_sigmas=np.asarray(sigmas, float).ravel()[:PARAMETERS],
        poses=poses,
        dropped=int(sum((~m).sum() for m in masks)),
    )
