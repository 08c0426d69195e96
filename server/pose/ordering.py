"""The four-fold ambiguity of a square (contract, "Coordinates").

A square looks the same after a quarter turn, so which image corner is model corner 0 is
a choice. Model corner 0 -> 1 runs along the beacon's +x_B axis (`server.geometry`); seen
from below by a camera of yaw `psi` under a beacon of yaw `beta`, that edge points along
the image angle `beta - psi` (x right, y down). With the device heading we expect that
angle; without it we assume |psi - beta| < 45 degrees, so we expect 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shared_schemas import OrientationRule


@dataclass(frozen=True)
class OrderedCorners:
    corners: np.ndarray  # (4, 2) in the model's corner order
    rule: OrientationRule


def _signed_area(points: list[list[float]]) -> float:
    return 0.5 * sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1], strict=True))


def order_corners(corners: np.ndarray, beacon_yaw_deg: float, heading_deg: float | None) -> OrderedCorners:
    """Corners (4, 2) in any cyclic order -> the model's order, by the contract's rule."""
    # Plain floats: for four corners Python arithmetic is several times faster than numpy's calls.
    points = corners.tolist()
    # Seen from below, the model's corners run with negative signed area in image coordinates.
    if not _signed_area(points) < 0:  # NaN corners turned as before (refused later as not finite)
        corners, points = corners[::-1], points[::-1]
    expected = math.radians(beacon_yaw_deg - heading_deg) if heading_deg is not None else 0.0
    best = min(range(4), key=lambda shift: _angle_off(points[shift], points[(shift + 1) % 4], expected))
    rule = OrientationRule.heading if heading_deg is not None else OrientationRule.yaw_within_45deg
    return OrderedCorners(corners=np.concatenate((corners[best:], corners[:best])), rule=rule)  # np.roll's rows


def _angle_off(first: list[float], second: list[float], expected_rad: float) -> float:
    """How far the edge first -> second turns from `expected_rad` (rad, 0 to pi)."""
    angle = math.atan2(second[1] - first[1], second[0] - first[0])
    return abs((angle - expected_rad + math.pi) % (2 * math.pi) - math.pi)
