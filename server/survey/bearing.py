"""Stage 4 of a survey: the map's compass bearing from the frames' compass readings.

A frame's `compass_bearing_deg` is the bearing (clockwise from north) of the image's +x laid
level, whose map yaw (counter-clockwise from +X) is the solved camera's yaw psi; the map's +X then
has the bearing psi + compass (docs/contract.md: `heading_deg` = `bearing_deg` -
`compass_bearing_deg`). Each frame gives one such value; the map's is their circular mean, and
its sigma their circular spread over the square root of their number. Indoor compass errors
(10-20 degrees, steel in the building) are partly shared by frames taken near each other, so that
sigma is a lower bound; the map needs the bearing only to tell a square's quarter turns apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import circmean, circstd

from server.geometry import ypr_from_rotation


@dataclass(frozen=True)
class Bearing:
    bearing_deg: float  # [0, 360)
    sigma_deg: float | None  # None from one frame: no spread to measure
    frames: int


def map_bearing(rotations_wc: list[np.ndarray], compass_bearings_deg: list[float | None]) -> Bearing | None:
    """The bearing of the map's +X from the frames that carry a compass reading; None if none does."""
    values = [
        ypr_from_rotation(rotation)[0] + compass
        for rotation, compass in zip(rotations_wc, compass_bearings_deg, strict=True)
        if compass is not None
    ]
    if not values:
        return None
    radians = np.radians(values)
    mean = math.degrees(float(circmean(radians))) % 360.0
    if len(values) == 1:
        return Bearing(mean, None, 1)
    return Bearing(mean, math.degrees(float(circstd(radians))) / math.sqrt(len(values)), len(values))
