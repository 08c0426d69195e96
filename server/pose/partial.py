"""Pose from the visible part of cut-off panels (beyond the paper: its transitions lose coverage).

Between two ceiling panels a phone often sees only parts of them; `locate` refuses a panel
that touches the frame border. Here the visible outline of one or more such panels (their
IDs already known from the device's track) is fitted directly:

- edge points: the panel's mid-level contour away from the frame border, each refined to a
  sub-pixel crossing of the mid level along its normal;
- model: the map's rounded square, projected with the camera's intrinsics and distortion,
  grown outward by `growth_px` (a clipped panel's mid-level contour lies outside its outline;
  the growth is measured on the session's complete panels by `measure_growth`, where the
  pose is known, since one partial panel cannot tell growth from distance);
- unknowns: yaw and the 3-D position; pitch and roll come from the gravity vector
  (g_camera = (sin p, -sin r cos p, -cos r cos p) for R_wc = Rz(y) Ry(p) Rx(r));
- residuals: the normal distance of each edge point to the grown projected outline, robust
  (Huber) least squares from the track's predicted pose.
The fit is accepted only when it converges with sub-pixel residuals and the position's
standard deviation from the Jacobian stays below `max_sigma_m`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial import cKDTree

from server.geometry import (
    beacon_outline_m,
    beacon_to_world,
    camera_matrix,
    dense_beacon_outline_m,
    distortion_vector,
    rotation_from_ypr,
)
from server.outcomes import Refusal
from server.vision.subpixel import level_crossings, profile_offsets, sample_profiles
from shared_schemas import Beacon, CameraIntrinsics, FailureReason


@dataclass(frozen=True)
class PartialRules:
    border_px: float = 3.0  # edge points this close to the frame border are the cut, not the panel
    max_points_per_panel: int = 500
    half_window_px: float = 5.0
    step_px: float = 0.25
    max_rms_px: float = 0.6
    max_sigma_m: float = 0.006
    min_points: int = 60


@dataclass(frozen=True)
class PartialFix:
    position_m: np.ndarray
    rotation_wc: np.ndarray
    rms_px: float
    sigma_m: float
    points: int
    growth_px: float


def tilt_from_gravity(gravity_camera: np.ndarray) -> tuple[float, float]:
    """(pitch, roll) in degrees of R_wc = Rz(yaw) Ry(pitch) Rx(roll) from gravity in the camera frame."""
    g = np.asarray(gravity_camera, float)
    g = g / np.linalg.norm(g)
    return math.degrees(math.asin(max(-1.0, min(1.0, g[0])))), math.degrees(math.atan2(-g[1], -g[2]))


def edge_points(
    pixels: np.ndarray, box: tuple[int, int, int, int], level: float, rules: PartialRules = PartialRules()
) -> np.ndarray:
    """Sub-pixel mid-level edge points (N, 2) of the blob in `box`, none near the frame border."""
    height, width = pixels.shape
    x, y, w, h = box
    margin = int(rules.half_window_px) + 4
    x0, y0 = max(0, x - margin), max(0, y - margin)
    x1, y1 = min(width, x + w + margin), min(height, y + h + margin)
    window = np.ascontiguousarray(pixels[y0:y1, x0:x1], dtype=np.float32)
    mask = (window > level).astype(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros((0, 2))
    contour = max(contours, key=cv2.contourArea).reshape(-1, 2).astype(float)
    # tangent from neighbours 3 steps apart; outward normal checked against the mask
    tangent = np.roll(contour, -3, axis=0) - np.roll(contour, 3, axis=0)
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    probe = np.clip(np.rint(contour + 2 * normal).astype(int), 0, [mask.shape[1] - 1, mask.shape[0] - 1])
    normal[mask[probe[:, 1], probe[:, 0]] > 0] *= -1
    full = contour + [x0, y0]
    keep = (
        (full[:, 0] > rules.border_px)
        & (full[:, 1] > rules.border_px)
        & (full[:, 0] < width - 1 - rules.border_px)
        & (full[:, 1] < height - 1 - rules.border_px)
    )
    contour, normal = contour[keep], normal[keep]
    if len(contour) > rules.max_points_per_panel:
        pick = np.linspace(0, len(contour) - 1, rules.max_points_per_panel).astype(int)
        contour, normal = contour[pick], normal[pick]
    if len(contour) == 0:
        return np.zeros((0, 2))
    offsets = profile_offsets(rules.half_window_px, rules.step_px, np.float64)
    shift = level_crossings(sample_profiles(window, contour, normal, offsets), offsets, level)
    found = np.isfinite(shift)
    points = contour[found] + shift[found, None] * normal[found] + [x0, y0]
    return points


def _outline_px(beacon: Beacon, position_m, rotation_wc, camera: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """Projected outline points (N, 2) about 1 px apart and their outward image normals."""
    rough = beacon_to_world(beacon, beacon_outline_m(beacon, 8))
    in_camera = (rough - position_m) @ rotation_wc
    span_px = camera.fx * beacon.size_m / max(float(in_camera[:, 2].min()), 1e-3)
    dense = dense_beacon_outline_m(beacon, span_px)
    world = beacon_to_world(beacon, dense)
    rvec, _ = cv2.Rodrigues(np.ascontiguousarray(rotation_wc.T))
    tvec = -rotation_wc.T @ position_m
    projected, _ = cv2.projectPoints(world, rvec, tvec, camera_matrix(camera), distortion_vector(camera))
    projected = projected.reshape(-1, 2)
    tangent = np.roll(projected, -1, axis=0) - np.roll(projected, 1, axis=0)
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    normal *= np.sign(np.sum(normal * (projected - projected.mean(axis=0)), axis=1))[:, None]
    return projected, normal


def _residuals(panels, position_m, rotation_wc, camera, growth_px) -> np.ndarray:
    parts = []
    for beacon, points in panels:
        outline, normal = _outline_px(beacon, position_m, rotation_wc, camera)
        _, nearest = cKDTree(outline).query(points)
        parts.append(np.sum((points - outline[nearest] - growth_px * normal[nearest]) * normal[nearest], axis=1))
    return np.concatenate(parts)


def measure_growth(beacon: Beacon, points: np.ndarray, position_m, rotation_wc, camera) -> float | None:
    """How far (px, outward) the mid-level contour lies from the outline of a panel of known pose."""
    if len(points) < 20:
        return None
    distances = _residuals(
        [(beacon, points)], np.asarray(position_m, float), np.asarray(rotation_wc, float), camera, 0.0
    )
    return float(np.median(distances))


def fit_partial(
    panels: list[tuple[Beacon, np.ndarray]],
    camera: CameraIntrinsics,
    gravity_camera,
    position_guess_m,
    yaw_guess_deg: float,
    growth_px: float | None,
    rules: PartialRules = PartialRules(),
) -> PartialFix | Refusal:
    """Camera pose from edge points of (partly visible) panels; or why there is none.

    `growth_px` None: the growth is fitted too (the rounded corners tell it from distance, weakly).
    """
    panels = [(b, p) for b, p in panels if len(p) > 0]
    count = sum(len(p) for _, p in panels)
    if count < rules.min_points:
        return Refusal(FailureReason.beacon_cut_off, f"only {count} edge points away from the frame border")
    if gravity_camera is None:
        return Refusal(FailureReason.beacon_cut_off, "a partial panel needs the gravity vector for its tilt")
    pitch, roll = tilt_from_gravity(gravity_camera)

    def unpack(params):
        return np.asarray(params[1:4]), rotation_from_ypr(params[0], pitch, roll)

    def residuals(params):
        position, rotation = unpack(params)
        return _residuals(panels, position, rotation, camera, params[4] if growth_px is None else growth_px)

    start = np.concatenate([[yaw_guess_deg], np.asarray(position_guess_m, float), [0.0] if growth_px is None else []])
    scale = [1.0, 0.01, 0.01, 0.01] + ([1.0] if growth_px is None else [])
    try:
        solution = least_squares(residuals, start, loss="huber", f_scale=1.0, x_scale=scale, max_nfev=200)
    except (ValueError, np.linalg.LinAlgError) as error:
        return Refusal(FailureReason.beacon_cut_off, f"the partial fit failed: {error}")
    final = solution.fun
    rms = float(np.sqrt(np.mean(final**2)))
    jacobian = solution.jac
    try:
        covariance = np.linalg.inv(jacobian.T @ jacobian) * max(rms, 0.1) ** 2
    except np.linalg.LinAlgError:
        return Refusal(FailureReason.beacon_cut_off, "the visible edges do not fix the position")
    sigma = float(np.sqrt(np.trace(covariance[1:4, 1:4])))
    if not solution.success or rms > rules.max_rms_px:
        return Refusal(FailureReason.beacon_cut_off, f"the visible edges do not fit the panels (RMS {rms:.2f} px)")
    if sigma > rules.max_sigma_m:
        return Refusal(
            FailureReason.beacon_cut_off, f"the visible edges fix the position only to {sigma * 1000:.0f} mm"
        )
    position, rotation = unpack(solution.x)
    return PartialFix(position, rotation, rms, sigma, count, float(solution.x[4]) if growth_px is None else growth_px)
