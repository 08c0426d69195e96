"""Stage 3: find the beacon's blob in a binary mask, and refuse blobs that are not it.

A blob is the beacon only if it looks like the map's panel seen from below (`PanelLook`: a
rounded square by default, or a rectangle's aspect, or a circle's fill):
- large enough to measure (`min_area_px`);
- convex (area / hull area): rejects two panels merged through a reflection or a gap;
- fills its minimum-area rectangle as the panel's outline does (a rounded square ~99 %, a
  circle 78.5 %), within a margin;
- the aspect (short / long side of that rectangle) of the panel, within a factor
  `min_aspect` either way: rejects windows, strip lights and two panels side by side.
  Tilts up to ~35 degrees stay within the default.
A blob that touches the frame border cannot be judged by its shape (only its convexity);
it is kept, flagged `cut`, when no whole blob passes: a later stage fits the visible part of
its outline. Among the blobs that pass, the largest wins (it is the nearest and best measured).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from server.outcomes import Refusal
from shared_schemas import Beacon, FailureReason


@dataclass(frozen=True)
class BlobRules:
    min_area_px: float = 40.0
    min_convexity: float = 0.93
    min_rectangle_fill: float = 0.88  # for the paper's panel (fill 0.99); others: their fill less as much
    min_aspect: float = 0.75  # of the panel's own aspect (short / long), either way

    max_fill_excess: float = 0.08  # above the panel's own fill: a square blob is not a round lamp


@dataclass(frozen=True)
class PanelLook:
    """How the panel's outline fills its bounding rectangle, and that rectangle's aspect."""

    fill: float = 1.0 - (4.0 - math.pi) * 0.115**2  # the paper's panel: a 0.174 m square, 0.02 m corners
    aspect: float = 1.0

    @classmethod
    def of(cls, beacon: Beacon) -> PanelLook:
        width, height = beacon.extent_m
        radius = beacon.outline_radius_m
        return cls(
            fill=1.0 - (4.0 - math.pi) * radius**2 / (width * height), aspect=min(width, height) / max(width, height)
        )


@dataclass(frozen=True)
class Blob:
    """One accepted blob: its outer contour (N, 2) int32 in the mask's pixels; `cut` when it
    touches the mask's border (only part of the panel is in view)."""

    contour: np.ndarray
    area_px: float
    bounding_box: tuple[int, int, int, int]  # x, y, width, height
    cut: bool = False


def _touches_border(box: tuple[int, int, int, int], shape: tuple[int, int]) -> bool:
    x, y, w, h = box
    return x <= 0 or y <= 0 or x + w >= shape[1] or y + h >= shape[0]


def convexity(contour: np.ndarray, area: float) -> float:
    """The contour's `area` over its convex hull's (1 for a convex outline)."""
    hull_area = cv2.contourArea(cv2.convexHull(contour))
    return area / hull_area if hull_area > 0 else 0.0


def _shape_problem(contour: np.ndarray, area: float, rules: BlobRules, look: PanelLook) -> str | None:
    """None when the contour looks like the panel, else a sentence saying why not."""
    solidity = convexity(contour, area)
    if solidity < rules.min_convexity:
        return f"its outline is not convex ({solidity:.2f} of its hull; two merged lights?)"
    (_, _), (rw, rh), _ = cv2.minAreaRect(contour)
    fill = area / (rw * rh) if rw * rh > 0 else 0.0
    min_fill = rules.min_rectangle_fill - (PanelLook().fill - look.fill)
    if fill < min_fill:
        return (
            f"it fills only {fill * 100:.0f} % of its bounding rectangle "
            f"(the panel fills {look.fill * 100:.0f} %, a round lamp 79 %)"
        )
    if fill > look.fill + rules.max_fill_excess:
        return f"it fills {fill * 100:.0f} % of its bounding rectangle (the round panel fills {look.fill * 100:.0f} %)"
    aspect = min(rw, rh) / max(rw, rh)
    if not look.aspect * rules.min_aspect <= aspect <= min(1.0, look.aspect / rules.min_aspect):
        return f"its sides are {aspect:.2f} : 1, the panel's {look.aspect:.2f} : 1 (a window or two panels?)"
    return None


def find_beacon_blob(mask: np.ndarray, rules: BlobRules = BlobRules(), look: PanelLook = PanelLook()) -> Blob | Refusal:
    """The beacon's blob in `mask` (uint8, 0 / 255), or the reason there is none: the largest
    whole blob that looks like the panel, else the largest convex blob cut by the border."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    candidates = sorted(((cv2.contourArea(c), c) for c in contours), key=lambda item: item[0], reverse=True)
    refusal: Refusal | None = None
    cut: Blob | None = None
    for area, contour in candidates:
        if area < rules.min_area_px:
            break
        x, y, w, h = cv2.boundingRect(contour)
        box = (x, y, w, h)
        if _touches_border(box, mask.shape):
            # A cut-off panel is not the panel's shape either: only its convexity can be judged.
            if cut is None and convexity(contour, area) >= rules.min_convexity:
                cut = Blob(contour=contour.reshape(-1, 2), area_px=area, bounding_box=box, cut=True)
            refusal = refusal or Refusal(FailureReason.beacon_cut_off, "the beacon touches the frame border")
            continue
        problem = _shape_problem(contour, area, rules, look)
        if problem is None:
            return Blob(contour=contour.reshape(-1, 2), area_px=area, bounding_box=box)
        refusal = refusal or Refusal(FailureReason.not_a_square, f"the brightest blob is not the beacon: {problem}")
    return cut or refusal or Refusal(FailureReason.no_beacon, "no bright blob large enough to be a beacon")
