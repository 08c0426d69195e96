"""Stages 4-6 of the paper (Section III-B3): from the beacon's contour to four corners.

Rounded corners (the paper's case b): convex hull (OpenCV's Sklansky), Ramer-Douglas-
Peucker with a tolerance small enough to keep the perimeter, the polygon as linked
segments, drop the short ones (the corner arcs: shorter than the mean), merge consecutive
collinear ones, keep the four longest and intersect neighbours. The result is the square
that circumscribes the rounded panel, whose corners are the model's corners.

Square corners (case a): RDP at 1 % of the perimeter must leave exactly four vertices.

Corners come out in the contour's cyclic order, integer-pixel accurate at best: they are
the starting guess of the sub-pixel stage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from server.outcomes import Refusal
from shared_schemas import FailureReason


@dataclass(frozen=True)
class PolygonRules:
    rdp_fraction: float = 0.002  # of the hull perimeter: keeps the perimeter within ~0.1 %
    merge_angle_deg: float = 8.0
    min_side_share: float = 0.5  # the four sides must make up this share of the perimeter


@dataclass(frozen=True)
class Quad:
    """Four corners (4, 2) float64 in cyclic order, in the contour's pixel coordinates."""

    corners: np.ndarray


def intersect_lines(p1: np.ndarray, p2: np.ndarray, q1: np.ndarray, q2: np.ndarray) -> np.ndarray | None:
    """Intersection of the line p1-p2 with the line q1-q2 (None if parallel)."""
    point = _intersect(*map(float, (*p1, *p2, *q1, *q2)))
    return None if point is None else np.array(point, dtype=float)


def _intersect(
    px: float, py: float, p2x: float, p2y: float, qx: float, qy: float, q2x: float, q2y: float
) -> tuple[float, float] | None:
    """`intersect_lines` in plain floats. Written out (Cramer's rule): np.cross costs ~20 us a call on 3-vectors."""
    rx, ry = p2x - px, p2y - py
    sx, sy = q2x - qx, q2y - qy
    denominator = rx * sy - ry * sx
    if abs(denominator) < 1e-12:
        return None
    t = ((qx - px) * sy - (qy - py) * sx) / denominator
    return px + t * rx, py + t * ry


def _merge_collinear(
    starts: list[list[float]], ends: list[list[float]], max_angle_deg: float
) -> list[tuple[list, list]]:
    """Merge runs of consecutive segments (cyclic) whose directions differ < `max_angle_deg`.

    starts, ends (n x 2 floats): the segments in order; a run is compared by its chord so far.
    Returns (start, end) pairs.
    """

    def direction(start, end) -> float:
        return math.degrees(math.atan2(end[1] - start[1], end[0] - start[0]))

    def collinear(a: list, b: list) -> bool:
        return abs((direction(*b) - direction(*a) + 180.0) % 360.0 - 180.0) < max_angle_deg

    merged: list[list] = []
    for start, end in zip(starts, ends, strict=True):
        if merged and collinear(merged[-1], [start, end]):
            merged[-1][1] = end
        else:
            merged.append([start, end])
    if len(merged) > 1 and collinear(merged[-1], merged[0]):
        merged[0][0] = merged[-1][0]
        merged.pop()
    return [(start, end) for start, end in merged]


def rounded_square_corners(contour: np.ndarray, rules: PolygonRules = PolygonRules()) -> Quad | Refusal:
    """Corners of the square circumscribing a rounded-square contour (N, 2)."""
    hull = cv2.convexHull(contour.reshape(-1, 1, 2).astype(np.float32))
    perimeter = cv2.arcLength(hull, True)
    # Plain floats from here: a polygon of a few dozen vertices costs less in Python than in numpy calls.
    polygon = cv2.approxPolyDP(hull, rules.rdp_fraction * perimeter, True).reshape(-1, 2).tolist()
    following = polygon[1:] + polygon[:1]
    lengths = np.hypot(
        [b[0] - a[0] for a, b in zip(polygon, following, strict=True)],
        [b[1] - a[1] for a, b in zip(polygon, following, strict=True)],
    ).tolist()
    # the corner arcs' short segments go (not "shorter than the mean": when RDP leaves one
    # vertex per corner, as for a large panel with small corners, that drops two real sides)
    shortest = 0.5 * max(lengths)
    kept = [k for k, length in enumerate(lengths) if length >= shortest]
    sides = _merge_collinear([polygon[k] for k in kept], [following[k] for k in kept], rules.merge_angle_deg)
    if len(sides) < 4:
        return Refusal(FailureReason.not_four_sides, f"the outline has {len(sides)} straight sides, not 4")
    side_lengths = np.hypot([end[0] - start[0] for start, end in sides], [end[1] - start[1] for start, end in sides])
    longest = sorted(np.argsort(side_lengths)[-4:].tolist())  # keep the contour's cyclic order
    if side_lengths[longest].sum() < rules.min_side_share * perimeter:
        return Refusal(FailureReason.not_four_sides, "the four longest sides cover too little of the outline")
    chosen = [sides[i] for i in longest]
    corners = []
    for previous, current in zip(chosen[-1:] + chosen[:-1], chosen, strict=True):
        corner = _intersect(*previous[0], *previous[1], *current[0], *current[1])
        if corner is None:
            return Refusal(FailureReason.not_four_sides, "two neighbouring sides are parallel")
        corners.append(corner)
    corners_array = np.array(corners)
    if not cv2.isContourConvex(corners_array.astype(np.float32).reshape(-1, 1, 2)):
        return Refusal(FailureReason.not_four_sides, "the four sides do not form a convex quadrilateral")
    return Quad(corners=corners_array)


def square_corners(contour: np.ndarray, rdp_fraction: float = 0.01) -> Quad | Refusal:
    """The paper's square-corner path: RDP at 1 % of the perimeter must leave 4 vertices."""
    closed = contour.reshape(-1, 1, 2)
    polygon = cv2.approxPolyDP(closed, rdp_fraction * cv2.arcLength(closed, True), True).reshape(-1, 2)
    if len(polygon) != 4:
        return Refusal(FailureReason.not_four_sides, f"RDP left {len(polygon)} vertices, not 4")
    return Quad(corners=polygon.astype(np.float64))
