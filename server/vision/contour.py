"""Stage 3: find the beacon's blob in a binary mask, and refuse blobs that are not it.

A blob is the beacon only if it looks like a (rounded) square seen from below:
- large enough to measure (`min_area_px`);
- convex (area / hull area): rejects two panels merged through a reflection or a gap;
- fills its minimum-area rectangle (a rounded square fills ~99 %, a round lamp 78.5 %);
- close to square (short / long side of that rectangle): rejects windows, strip lights
  and two panels side by side. Tilts up to ~35 degrees stay above the default limit.
- not touching the frame border: a cut-off panel gives a biased fix, so it is refused
  with its own reason (a later stage may reconstruct it).
Among the blobs that pass, the largest wins (it is the nearest and best measured).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.outcomes import Refusal
from shared_schemas import FailureReason


@dataclass(frozen=True)
class BlobRules:
    min_area_px: float = 40.0
    min_convexity: float = 0.93
    min_rectangle_fill: float = 0.88
    min_aspect: float = 0.75


@dataclass(frozen=True)
class Blob:
    """One accepted blob: its outer contour (N, 2) int32 in the mask's pixels."""

    contour: np.ndarray
    area_px: float
    bounding_box: tuple[int, int, int, int]  # x, y, width, height


def _touches_border(box: tuple[int, int, int, int], shape: tuple[int, int]) -> bool:
    x, y, w, h = box
    return x <= 0 or y <= 0 or x + w >= shape[1] or y + h >= shape[0]


def _shape_problem(contour: np.ndarray, area: float, rules: BlobRules) -> str | None:
    """None when the contour looks like a rounded square, else a sentence saying why not."""
    hull_area = cv2.contourArea(cv2.convexHull(contour))
    convexity = area / hull_area if hull_area > 0 else 0.0
    if convexity < rules.min_convexity:
        return f"its outline is not convex ({convexity:.2f} of its hull; two merged lights?)"
    (_, _), (rw, rh), _ = cv2.minAreaRect(contour)
    fill = area / (rw * rh) if rw * rh > 0 else 0.0
    if fill < rules.min_rectangle_fill:
        return f"it fills only {fill:.0%} of its bounding rectangle (a round lamp fills 79 %)"
    aspect = min(rw, rh) / max(rw, rh)
    if aspect < rules.min_aspect:
        return f"its sides differ too much ({aspect:.2f} : 1; a window or two panels?)"
    return None


def find_beacon_blob(mask: np.ndarray, rules: BlobRules = BlobRules()) -> Blob | Refusal:
    """The beacon's blob in `mask` (uint8, 0 / 255), or the reason there is none."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    candidates = sorted(((cv2.contourArea(c), c) for c in contours), key=lambda item: item[0], reverse=True)
    refusal: Refusal | None = None
    for area, contour in candidates:
        if area < rules.min_area_px:
            break
        x, y, w, h = cv2.boundingRect(contour)
        box = (x, y, w, h)
        # A cut-off panel is not square either: say the truer thing first.
        if _touches_border(box, mask.shape):
            refusal = refusal or Refusal(FailureReason.beacon_cut_off, "the beacon touches the frame border")
            continue
        problem = _shape_problem(contour, area, rules)
        if problem is None:
            return Blob(contour=contour.reshape(-1, 2), area_px=area, bounding_box=box)
        refusal = refusal or Refusal(FailureReason.not_a_square, f"the brightest blob is not the beacon: {problem}")
    return refusal or Refusal(FailureReason.no_beacon, "no bright blob large enough to be a beacon")
