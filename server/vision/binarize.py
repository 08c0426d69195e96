"""Stages 1-2 of the paper (Section III-B2): blur, then threshold.

The level is chosen per frame from its own histogram, so it follows exposure and ambient
light: half-way between the background (the median, since the panel covers far less than
half of any frame it is located in) and the panel's plateau (a high percentile of the
brightest pixels, which for an overexposed panel is the saturation level). Half-way is the
level at which a blurred step edge crosses its true position when it is not clipped; the
clipped-edge bias that remains is removed later, from the grey levels (`subpixel.py`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from shared_schemas.windows import PLATEAU_FRACTION, histogram_levels


@dataclass(frozen=True)
class Levels:
    """Grey levels of one frame, in DN."""

    background: float
    plateau: float

    @property
    def threshold(self) -> float:
        return (self.background + self.plateau) / 2.0

    @property
    def contrast(self) -> float:
        return self.plateau - self.background


def estimate_levels(image: np.ndarray, plateau_fraction: float = PLATEAU_FRACTION) -> Levels:
    """Background and plateau levels of an 8-bit image from one histogram pass.

    `plateau_fraction`: the share of pixels counted as "brightest"; small enough that a
    panel covering 0.02 % of the frame still sets the plateau.
    """
    return Levels(*histogram_levels(image, plateau_fraction))


def blur(image: np.ndarray, kernel_px: int = 5) -> np.ndarray:
    """Box blur that removes pixel noise before thresholding (odd `kernel_px`).

    A box rather than a Gaussian: OpenCV runs it as running sums, 3-4x faster on a
    region of interest, and being symmetric it leaves the mid level of a straight edge where
    it was. The blurred mask only seeds the sub-pixel stage, which reads the raw pixels.
    """
    return cv2.blur(image, (kernel_px, kernel_px))


def threshold(image: np.ndarray, levels: Levels) -> np.ndarray:
    """Binary mask (0 / 255, uint8) of the pixels brighter than the levels' mid level."""
    _, mask = cv2.threshold(image, levels.threshold, 255, cv2.THRESH_BINARY)
    return mask
