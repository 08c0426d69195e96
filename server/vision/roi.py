"""Stage 0 (beyond the paper): find the beacon on a subsampled view, so that the fine
stages read only its region of interest.

Taking every `step`-th pixel of every `step`-th row reads 1/step of the frame's memory
(whole cache lines of the kept rows), so a 20-megapixel frame costs about one read of a
tenth of it. The same blob rules as the fine stage run on the small view, so a frame
without a usable beacon is refused before any full-resolution work.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.outcomes import Refusal
from server.vision.binarize import Levels, threshold
from server.vision.contour import BlobRules, PanelLook, find_beacon_blob
from shared_schemas import FailureReason, FrameMeta
from shared_schemas.windows import (
    COARSE_SHORT_SIDE_PX,
    ROI_MARGIN_PX,
    coarse_step,
    coarse_view,
    grey_level_counts,
    view_levels,
)


@dataclass(frozen=True)
class CoarseRules:
    """The subsampled view that both coarse stages read: this one (one panel) and
    `server.vision.beacons` (every panel). `RoiRules` and `beacons.CandidateRules` extend it,
    so its defaults are written once."""

    coarse_short_side_px: int = COARSE_SHORT_SIDE_PX  # the view's short side is at least this (the contract's)
    min_contrast_dn: float = 20.0  # plateau - background below this: nothing stands out, no beacon

    def coarse_step(self, shape: tuple[int, ...]) -> int:
        """Subsampling step for a frame of `shape` (height, width): 1 for frames smaller than the view."""
        return coarse_step(shape[0], shape[1], self.coarse_short_side_px)


@dataclass(frozen=True)
class FrameView:
    """Where a frame's pixels sit in the sensor frame, and that frame's levels when the client
    measured them. A window (`crop`) is read on the full frame's coarse grid with the full
    frame's levels, so that it finds the same blob, region and edges as the whole frame: the
    window then gives the whole frame's answer (docs/contract.md, "Windows")."""

    full_size: tuple[int, int] = (0, 0)  # (width, height); (0, 0): the pixels are the whole frame
    offset: tuple[int, int] = (0, 0)  # (column, row) of the pixels' first pixel in the full frame
    levels: Levels | None = None
    # ID frames: frame rows of the longest dark run between a panel's stripes (the code's longest low run
    # plus the exposure: `server.vlc.capture.stripe_gap_rows`, which knows the code), bridged along the
    # columns by `server.vision.beacons`; 0: the frame carries no stripes
    stripe_gap_rows: int = 0

    @classmethod
    def of(cls, meta: FrameMeta, stripe_gap_rows: int = 0) -> FrameView:
        crop = meta.crop
        if crop is None:
            return cls(stripe_gap_rows=stripe_gap_rows)
        levels = Levels(*crop.levels_dn) if crop.levels_dn else None
        return cls((crop.full_width, crop.full_height), (crop.x, crop.y), levels, stripe_gap_rows)

    def grid(self, shape: tuple[int, ...], rules: CoarseRules) -> tuple[int, tuple[int, int]]:
        """The coarse view's step and its first (column, row) in pixels of `shape` (height, width):
        every `step`-th pixel of the full frame, wherever the window starts."""
        width, height = self.full_size if self.full_size != (0, 0) else (shape[1], shape[0])
        step = rules.coarse_step((height, width))
        return step, (-self.offset[0] % step, -self.offset[1] % step)


def coarse_levels(small: np.ndarray) -> Levels:
    """The frame's levels from its coarse view (the contract's rule: `crop.levels_dn`)."""
    return Levels(*view_levels(small, _grey_level_counts))


def _grey_level_counts(samples: np.ndarray) -> np.ndarray:
    """`grey_level_counts` by OpenCV: ~3x faster than `np.bincount`, which first widens every sample to
    int64; its float32 counts are whole numbers, exact below 2^24 samples (a coarse view has < 2^20)."""
    if samples.size >= 1 << 24:
        return grey_level_counts(samples)
    return cv2.calcHist([samples], [0], None, [256], [0, 256]).ravel()


@dataclass(frozen=True)
class RoiRules(CoarseRules):
    margin_px: int = ROI_MARGIN_PX  # clients grow their windows by it (shared_schemas.windows)


@dataclass(frozen=True)
class Roi:
    """Where to look at full resolution: x0:x1, y0:y1 of the frame, and the frame's levels."""

    x0: int
    y0: int
    x1: int
    y1: int
    levels: Levels
    step: int


def coarse_to_frame(
    points: np.ndarray, step: int, shape: tuple[int, int], origin: tuple[int, int] = (0, 0)
) -> np.ndarray:
    """Frame pixel coordinates (..., 2) x, y of `coarse_view` pixel coordinates (..., 2) x, y.

    Whole view pixels land exactly on the frame pixel they were read from: `step` times from the
    origin, except the view's extra last column and row, which are the frame's last (closer).
    """
    height, width = shape
    return np.minimum(np.asarray(points, dtype=float) * step + origin, [width - 1, height - 1])


def find_roi(
    pixels: np.ndarray,
    rules: RoiRules = RoiRules(),
    blob_rules: BlobRules = BlobRules(),
    look: PanelLook = PanelLook(),
    view: FrameView = FrameView(),
) -> Roi | Refusal:
    """The beacon's region of interest in a frame (height, width) uint8 (the panel's blob may be
    cut by the frame border: see `contour.find_beacon_blob`); `view` places a window."""
    height, width = pixels.shape
    step, origin = view.grid(pixels.shape, rules)
    mask, levels = _coarse_mask(pixels, rules, view)
    if levels.contrast < rules.min_contrast_dn:
        return Refusal(
            FailureReason.no_beacon,
            f"nothing stands out of the background (contrast {levels.contrast:.0f} DN)",
        )
    blob = find_beacon_blob(mask, blob_rules, look)
    if isinstance(blob, Refusal):
        return blob
    x, y, w, h = blob.bounding_box
    margin = rules.margin_px + 2 * step
    column0, row0 = origin
    return Roi(
        x0=max(0, column0 + x * step - margin),
        y0=max(0, row0 + y * step - margin),
        x1=min(width, column0 + (x + w) * step + margin),
        y1=min(height, row0 + (y + h) * step + margin),
        levels=levels,
        step=step,
    )


def _coarse_mask(pixels: np.ndarray, rules: CoarseRules, view: FrameView) -> tuple[np.ndarray, Levels]:
    """The coarse view's mask above the mid level, and the levels."""
    step, origin = view.grid(pixels.shape, rules)
    small = coarse_view(pixels, step, origin)
    levels = view.levels or coarse_levels(small)
    # No blur here: it would spread a panel a few pixels from the frame edge onto the border
    # of the small view, and at this scale the panel stands hundreds of DN above the noise.
    return threshold(small, levels), levels


def brightest_blob_px(
    pixels: np.ndarray, rules: RoiRules = RoiRules(), view: FrameView = FrameView()
) -> np.ndarray | None:
    """The outer contour (N, 2) in frame pixels of the largest blob `find_roi` judged, or None: what a
    refusal at this stage saw (for pictures; `server.diagnostics`)."""
    step, origin = view.grid(pixels.shape, rules)
    mask, _ = _coarse_mask(pixels, rules, view)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    largest = max(contours, key=cv2.contourArea).reshape(-1, 2)
    return coarse_to_frame(largest, step, pixels.shape[:2], origin)
