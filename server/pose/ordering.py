"""The four-fold ambiguity of a square (contract, "Coordinates").

A square looks the same after a quarter turn, so which image corner is model corner 0 is
a choice. Model corner 0 -> 1 runs along the beacon's +x_B axis (`server.geometry`); seen
from below by a camera of yaw `psi` under a beacon of yaw `beta`, that edge points along
the image angle `beta - psi` (x right, y down). With the device heading we expect that
angle; without it we assume |psi - beta| < 45 degrees, so we expect 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shared_schemas import OrientationRule


@dataclass(frozen=True)
class OrderedCorners:
    corners: np.ndarray  # (4, 2) in the model's corner order
    rule: OrientationRule


def _signed_area(points: np.ndarray) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def order_corners(corners: np.ndarray, beacon_yaw_deg: float, heading_deg: float | None) -> OrderedCorners:
    """Corners (4, 2) in any cyclic order -> the model's order, by the contract's rule."""
    # Seen from below, the model's corners run with negative signed area in image coordinates.
    cyclic = corners if _signed_area(corners) < 0 else corners[::-1]
    expected = np.radians(beacon_yaw_deg - heading_deg) if heading_deg is not None else 0.0
    best = min(range(4), key=lambda shift: _angle_off(np.roll(cyclic, -shift, axis=0), expected))
    rule = OrientationRule.heading if heading_deg is not None else OrientationRule.yaw_within_45deg
    return OrderedCorners(corners=np.roll(cyclic, -best, axis=0), rule=rule)


def _angle_off(corners: np.ndarray, expected_rad: float) -> float:
    dx, dy = corners[1] - corners[0]
    return abs((np.arctan2(dy, dx) - expected_rad + np.pi) % (2 * np.pi) - np.pi)
