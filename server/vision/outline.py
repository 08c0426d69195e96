"""Sub-pixel points on the visible outline of one bright blob (beyond the paper).

The corner path (`contour`, `polygon`, `subpixel`) needs the whole rounded square; the outline
fit (`server.pose.outline`) needs only points on whatever part of the panel's outline is in
view. Here they are taken from the blob's mid-level contour in a window of the frame, each
moved along its outward normal to the sub-pixel crossing of the mid level (the profiles of
`subpixel`), and left out where they do not belong to the panel:
- within `border_px` of the frame border: there the contour runs along the cut, not the panel;
- within `neighbour_px` of another bright blob: its light overlaps the profile.

The points' own noise is measured here too, without any model of the panel: the scatter of each
point about the chord of its two neighbours along short runs of the outline (`edge_noise_px`),
what the outline fit's residuals must come down to if the model is the right shape
(`server.pose.shape`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.vision.binarize import Levels
from server.vision.subpixel import level_crossings, pedestal_levels, profile_offsets, sample_profiles


@dataclass(frozen=True)
class OutlineRules:
    border_px: float = 6.0  # contour points this close to the frame border are the cut, not the panel
    # (and their profiles, half_window_px long, would read past it)
    neighbour_px: float = 8.0  # nor those this close to another bright blob
    half_window_px: float = 5.0
    step_px: float = 0.25
    max_points: int = 600  # evenly spread along the contour: enough for a 0.1 px fit, cheap to fit


@dataclass(frozen=True)
class OutlinePoints:
    """Points (N, 2) on the blob's mid-level outline, frame pixels (distorted), in contour order;
    `level_gap_px`, the
    median distance from the mid-level to the quarter-level crossing (the edge's blur, NaN
    when unmeasured; `server.vision.subpixel.blur_sigma_px`); `edge_noise_px`, one point's
    noise across the edge (`run_scatter_px`, NaN with too few points)."""

    points_px: np.ndarray
    level_gap_px: float = float("nan")
    edge_noise_px: float = float("nan")


MIN_RUN_POINTS = 12  # fewer triples of neighbours than this measure no scatter


def run_scatter_px(points_px: np.ndarray, trend_points: int = 15) -> float:
    """The noise (px, 1 sigma) of points (N, 2) along a smooth edge, in contour order.

    Each point's signed distance from the chord of its two neighbours is its own error less the
    mean of theirs, plus the curve's sagitta (h^2 / 2R for spacing h, radius R): the sagitta
    changes slowly along the outline and a running median of `trend_points` removes it; what is
    left has variance 1.5 sigma^2 for independent errors (1 + 1/4 + 1/4). Triples across a gap
    (the frame border, a neighbour's light) are left out. Robust: 1.4826 MAD. NaN with fewer
    than `MIN_RUN_POINTS` triples.
    """
    if len(points_px) < MIN_RUN_POINTS + 2:
        return float("nan")
    before, here, after = points_px[:-2], points_px[1:-1], points_px[2:]
    chord = after - before
    length = np.linalg.norm(chord, axis=1)
    spacing = np.linalg.norm(np.diff(points_px, axis=0), axis=1)
    typical = float(np.median(spacing))
    joined = (spacing[:-1] < 2.5 * typical) & (spacing[1:] < 2.5 * typical) & (length > 1e-9)
    if joined.sum() < MIN_RUN_POINTS:
        return float("nan")
    offset = here - before
    sagitta = (chord[:, 0] * offset[:, 1] - chord[:, 1] * offset[:, 0]) / np.maximum(length, 1e-9)
    sagitta = sagitta[joined]
    half = trend_points // 2
    padded = np.pad(sagitta, half, mode="edge")
    trend = np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1), axis=1)
    left = sagitta - trend
    return float(1.4826 * np.median(np.abs(left - np.median(left))) / np.sqrt(1.5))


def _outward_normals(contour: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Unit normals (N, 2) of a closed pixel contour, pointing out of `mask`'s blob."""
    tangent = np.roll(contour, -3, axis=0) - np.roll(contour, 3, axis=0)
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    probe = np.clip(np.rint(contour + 2 * normal).astype(int), 0, [mask.shape[1] - 1, mask.shape[0] - 1])
    normal[mask[probe[:, 1], probe[:, 0]] > 0] *= -1
    return normal


def outline_points(
    pixels: np.ndarray, box: tuple[int, int, int, int], levels: Levels, rules: OutlineRules = OutlineRules()
) -> OutlinePoints:
    """The visible outline of the largest blob above the mid level in `box` (x, y, w, h) of the frame."""
    level, background = levels.threshold, levels.background
    height, width = pixels.shape
    x, y, w, h = box
    margin = int(rules.half_window_px + rules.neighbour_px) + 2
    x0, y0 = max(0, x - margin), max(0, y - margin)
    x1, y1 = min(width, x + w + margin), min(height, y + h + margin)
    window = pixels[y0:y1, x0:x1]  # a view: OpenCV reads it in place, no copy of the box
    _, mask = cv2.threshold(window, level, 1, cv2.THRESH_BINARY)  # uint8: the same as window > level
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return OutlinePoints(np.zeros((0, 2)))
    largest = max(range(len(contours)), key=lambda i: cv2.contourArea(contours[i]))
    contour = contours[largest].reshape(-1, 2).astype(float)
    normal = _outward_normals(contour, mask)
    full = contour + [x0, y0]
    keep = (
        (full[:, 0] > rules.border_px)
        & (full[:, 1] > rules.border_px)
        & (full[:, 0] < width - 1 - rules.border_px)
        & (full[:, 1] < height - 1 - rules.border_px)
    )
    if len(contours) > 1:
        others = np.full(mask.shape, 255, np.uint8)
        cv2.drawContours(others, [c for i, c in enumerate(contours) if i != largest], -1, 0, cv2.FILLED)
        distance = cv2.distanceTransform(others, cv2.DIST_L2, 3)
        keep &= distance[contour[:, 1].astype(int), contour[:, 0].astype(int)] > rules.neighbour_px
    if keep.sum() > rules.max_points:
        pick = np.flatnonzero(keep)[np.linspace(0, keep.sum() - 1, rules.max_points).astype(int)]
        keep = np.zeros_like(keep)
        keep[pick] = True
    contour, normal = contour[keep], normal[keep]
    if len(contour) == 0:
        return OutlinePoints(np.zeros((0, 2)))
    offsets = profile_offsets(rules.half_window_px, rules.step_px, np.float64)
    profiles = sample_profiles(window, contour, normal, offsets)
    shift = level_crossings(profiles, offsets, level)
    edge_levels = pedestal_levels(profiles, offsets, shift, levels)
    if edge_levels != levels:
        level, background = edge_levels.threshold, edge_levels.background
        shift = level_crossings(profiles, offsets, level)
    gap = level_crossings(profiles, offsets, (level + background) / 2) - shift
    found = np.isfinite(shift)
    points = contour[found] + shift[found, None] * normal[found] + [x0, y0]
    return OutlinePoints(points, _median(gap), run_scatter_px(points))


def _median(values: np.ndarray) -> float:
    return float(np.nanmedian(values)) if np.isfinite(values).any() else float("nan")
