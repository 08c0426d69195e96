"""Stage 4 of a survey: the map's compass bearing from the frames' compass readings.

A frame's `compass_bearing_deg` is the bearing (clockwise from north) of the image's +x laid
level, whose map yaw (counter-clockwise from +X) is the solved camera's yaw psi; the map's +X then
has the bearing psi + compass (docs/contract.md: `heading_deg` = `bearing_deg` -
`compass_bearing_deg`). Each frame gives one such value; the map's is their circular mean.

Its sigma has two parts. A building's steel and wiring deflect the field alike over a room, so
the frames of one survey share one error that no number of frames averages away and that they
cannot show (their spread is the same with or without it): its size is a stated prior,
`SurveyRules.compass_bias_sigma_deg` (10 degrees: indoor phone headings err by 10-20 degrees,
docs/survey.md). Each frame's own noise (the hand, local anomalies) does average: their circular
spread over the square root of their number. The sigma is the two added in quadrature; the map
needs the bearing only to tell a square's quarter turns apart (45 degrees off).
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


def map_bearing(
    rotations_wc: list[np.ndarray], compass_bearings_deg: list[float | None], bias_sigma_deg: float
) -> Bearing | None:
    """The bearing of the map's +X from the frames that carry a compass reading; None if none does.
    `bias_sigma_deg`: the 1-sigma of the error all the frames share (degrees)."""
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
    noise_deg = math.degrees(float(circstd(radians))) / math.sqrt(len(values))
    return Bearing(mean, math.hypot(bias_sigma_deg, noise_deg), len(values))
