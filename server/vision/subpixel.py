"""Stage 7 (beyond the paper): sub-pixel sides from the grey levels, with the clipped-edge bias removed.

The polygon stage gives corners good to a pixel or so. Here each side is measured again
from the image itself, in the way of AprilTag's edge refinement:

1. Along the straight part of each side (away from the rounded corners) grey-level profiles
   are sampled across the edge (bilinear, 0.25 px steps), and each profile's crossing of the
   frame's mid level is found to a fraction of a pixel.
2. The crossings are undistorted (when the camera has distortion) and a line is fitted to
   each side (OpenCV's robust `fitLine`).
3. The mid-level crossing of a *clipped* edge is not the true edge (contract, "Physics"):
   the PSF spreads the saturated light outward, so the panel looks too big. All profiles,
   aligned on their own crossings, are pooled into one edge profile and fitted with the
   model of a blurred, clipped step, `min(sat, b + A * Phi((e - x) / s))`; the fitted edge
   offset `e` moves the four lines to the true edges. For a panel that does not saturate the
   model fits with `e` close to 0, so the same code serves both.
4. Neighbouring lines intersect at the corners of the circumscribed square.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.special import ndtr

from server.vision.binarize import Levels

SATURATION_DN = 255.0


@dataclass(frozen=True)
class EdgeRules:
    half_window_px: float = 8.0
    step_px: float = 0.25
    max_profiles_per_side: int = 200
    corner_margin: float = 0.03  # of the side, kept clear beyond the corner arcs
    bin_px: float = 0.1


@dataclass(frozen=True)
class EdgeFit:
    """Refined sides and corners in undistorted full-frame pixel coordinates.

    `lines` (4, 3): a x + b y + c = 0 with (a, b) the unit outward normal; side k joins
    corner k to corner k + 1. `edge_shift_px`: how far the true edges lie outward of the
    mid-level crossings (negative: inward, as for an overexposed panel).
    """

    corners: np.ndarray
    lines: np.ndarray
    edge_shift_px: float
    edge_blur_px: float
    line_rms_px: float
    points_per_side: tuple[int, ...]
    warnings: tuple[str, ...] = ()


def _outward_normals(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit directions, outward normals and lengths of the four sides of a convex quad."""
    starts, ends = corners, np.roll(corners, -1, axis=0)
    directions = ends - starts
    lengths = np.linalg.norm(directions, axis=1)
    directions = directions / lengths[:, None]
    normals = np.stack([directions[:, 1], -directions[:, 0]], axis=1)
    outward = np.sign(np.sum(normals * ((starts + ends) / 2 - corners.mean(axis=0)), axis=1))
    return directions, normals * outward[:, None], lengths


def _mid_level_crossings(profiles: np.ndarray, offsets: np.ndarray, level: float) -> np.ndarray:
    """Offset of each profile's bright-to-dark crossing of `level` nearest to 0 (NaN if none)."""
    above, below = profiles[:, :-1], profiles[:, 1:]
    crossing = (above >= level) & (below < level)
    distance = np.where(crossing, np.abs(offsets[:-1]), np.inf)
    j = np.argmin(distance, axis=1)
    rows = np.arange(len(profiles))
    v0, v1 = above[rows, j], below[rows, j]
    fraction = (v0 - level) / np.maximum(v0 - v1, 1e-9)
    result = offsets[j] + fraction * (offsets[1] - offsets[0])
    return np.where(np.isfinite(distance[rows, j]), result, np.nan)


def _fit_clipped_edge(
    distance: np.ndarray, value: np.ndarray, levels: Levels, rules: EdgeRules
) -> tuple[float, float] | None:
    """(edge offset, blur sigma) of a pooled edge profile; None when it cannot be fitted.

    `distance` is outward from each profile's own mid-level crossing, in pixels.
    """
    bins = np.round(distance / rules.bin_px).astype(np.int64)
    bins -= bins.min()
    counts = np.bincount(bins)
    sums = np.bincount(bins, weights=value)
    filled = counts >= 3
    x = (np.nonzero(filled)[0] + np.round(distance.min() / rules.bin_px)) * rules.bin_px
    y = sums[filled] / counts[filled]
    clipped = levels.plateau >= SATURATION_DN - 1
    if len(x) < 8:
        return None
    background = float(np.min(y))
    amplitude0 = (SATURATION_DN - background) * (2.0 if clipped else 1.0)

    def residual(p: np.ndarray) -> np.ndarray:
        b, a, e, s = p
        # Where the panel saturates the model clips too: the clip point pins the amplitude.
        return np.minimum(b + a * ndtr((e - x) / s), SATURATION_DN) - y

    def jacobian(p: np.ndarray) -> np.ndarray:
        b, a, e, s = p
        u = (e - x) / s
        density = np.exp(-0.5 * u * u) / np.sqrt(2 * np.pi)
        columns = np.column_stack([np.ones_like(u), ndtr(u), a * density / s, -a * density * u / s])
        columns[b + a * ndtr(u) >= SATURATION_DN] = 0.0  # clipped: the model does not move
        return columns

    span = rules.half_window_px
    x0 = np.array([background, amplitude0, 0.0, 1.0])
    lower = [0.0, 0.2 * amplitude0, -span, 0.1]
    upper = [levels.threshold, 200.0 * amplitude0, span, span]
    fit = least_squares(residual, x0, jac=jacobian, bounds=(lower, upper),
                        x_scale=[10.0, amplitude0, 0.5, 0.5])
    if not fit.success:
        return None
    return float(fit.x[2]), float(fit.x[3])


def _pixels_across_sides(image, bases, crossings, normals, valid, rules: EdgeRules):
    """(distance, value) of the real pixels near each side's mid-level line.

    Pixels, not interpolated samples: bilinear interpolation would bend the two or three
    unclipped pixels of an overexposed edge into straight pieces and hide its shape.
    `distance` is outward from the line through the side's crossings, in pixels.
    """
    distances, values = [], []
    n_along = bases.shape[1]
    for k in range(4):
        side = slice(k * n_along, (k + 1) * n_along)
        ok = valid[side]
        if ok.sum() < 3:
            continue
        crossing_points = bases[k][ok] + crossings[side][ok, None] * normals[k]
        line, _ = _line_through(crossing_points, normals[k])
        normal, offset = line[:2], -line[2]
        # Walk the side along its main axis; at each step take the pixels across the line.
        axis = 0 if abs(normal[1]) > abs(normal[0]) else 1  # 0: mostly horizontal side
        lo = int(np.ceil(crossing_points[:, axis].min()))
        hi = int(np.floor(crossing_points[:, axis].max()))
        steps = np.arange(lo, hi + 1)
        across_at = (offset - normal[axis] * steps) / normal[1 - axis]  # the line's other coordinate
        band = np.arange(-int(rules.half_window_px) - 1, int(rules.half_window_px) + 2)
        other = np.rint(across_at)[:, None].astype(int) + band[None, :]
        main = np.broadcast_to(steps[:, None], other.shape)
        xs, ys = (main, other) if axis == 0 else (other, main)
        inside = (xs >= 0) & (ys >= 0) & (xs < image.shape[1]) & (ys < image.shape[0])
        xs, ys = xs[inside], ys[inside]
        distance = xs * normal[0] + ys * normal[1] - offset
        keep = np.abs(distance) <= rules.half_window_px
        distances.append(distance[keep])
        values.append(image[ys[keep], xs[keep]])
    return np.concatenate(distances), np.concatenate(values).astype(float)


def _line_through(points: np.ndarray, outward: np.ndarray) -> tuple[np.ndarray, float]:
    """Robust line (a, b, c) through points, (a, b) pointing along `outward`; and its RMS."""
    vx, vy, x0, y0 = cv2.fitLine(points.astype(np.float32), cv2.DIST_HUBER, 0, 0.01, 0.01).ravel()
    normal = np.array([vy, -vx], dtype=float)
    if normal @ outward < 0:
        normal = -normal
    c = -float(normal @ [x0, y0])
    residuals = points @ normal + c
    return np.array([normal[0], normal[1], c]), float(np.sqrt(np.mean(residuals**2)))


def refine_edges(
    roi: np.ndarray,
    roi_origin: tuple[int, int],
    corners: np.ndarray,
    levels: Levels,
    straight_fraction: float,
    camera_matrix: np.ndarray,
    distortion: np.ndarray | None,
    rules: EdgeRules = EdgeRules(),
) -> EdgeFit | None:
    """Sub-pixel sides and corners of the beacon.

    roi: the raw (unblurred) grey levels around the beacon; roi_origin: its (x, y) in the
    frame; corners (4, 2): starting corners in ROI pixels, cyclic order; straight_fraction:
    the share of each side that is straight (1 - 2 r / side). Returns None when a side has
    too few edge points to fit.
    """
    image = roi.astype(np.float32)
    directions, normals, lengths = _outward_normals(corners)
    n_along = int(np.clip(lengths.min() / 2, 12, rules.max_profiles_per_side))
    start = (1.0 - straight_fraction) / 2 + rules.corner_margin
    along = np.linspace(start, 1.0 - start, n_along)
    offsets = np.arange(-rules.half_window_px, rules.half_window_px + 1e-9, rules.step_px)

    bases = corners[:, None, :] + along[None, :, None] * (lengths[:, None, None] * directions[:, None, :])
    samples = bases[:, :, None, :] + offsets[None, None, :, None] * normals[:, None, None, :]
    flat = samples.reshape(-1, len(offsets), 2).astype(np.float32)
    profiles = cv2.remap(image, flat[..., 0], flat[..., 1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan"))
    crossings = _mid_level_crossings(profiles, offsets, levels.threshold)

    warnings: list[str] = []
    pooled = np.isfinite(crossings) & np.all(np.isfinite(profiles), axis=1)
    edge = _fit_clipped_edge(*_pixels_across_sides(image, bases, crossings, normals, pooled, rules), levels, rules)
    if edge is None:
        warnings.append("edge profile could not be fitted: sides taken at the mid level")
        edge = (0.0, float("nan"))
    shift, blur_px = edge

    points = bases.reshape(-1, 2) + crossings[:, None] * np.repeat(normals, n_along, axis=0)
    points = points + np.asarray(roi_origin, dtype=float)
    if distortion is not None:
        points = cv2.undistortPoints(points.reshape(-1, 1, 2), camera_matrix, distortion,
                                     P=camera_matrix).reshape(-1, 2)
    lines, rms, counts = [], [], []
    for k in range(4):
        side = slice(k * n_along, (k + 1) * n_along)
        valid = pooled[side]
        if valid.sum() < max(6, n_along // 3):
            return None
        line, line_rms = _line_through(points[side][valid], normals[k])
        line[2] -= shift  # move the line outward by `shift` along its normal
        lines.append(line)
        rms.append(line_rms)
        counts.append(int(valid.sum()))
    lines_array = np.array(lines)
    corner_points = np.cross(np.roll(lines_array, 1, axis=0), lines_array)
    refined = corner_points[:, :2] / corner_points[:, 2:3]
    return EdgeFit(
        corners=refined,
        lines=lines_array,
        edge_shift_px=shift,
        edge_blur_px=blur_px,
        line_rms_px=float(np.sqrt(np.mean(np.square(rms)))),
        points_per_side=tuple(counts),
        warnings=tuple(warnings),
    )
