"""Stage 0 (beyond the paper): find the beacon on a subsampled view, so that the fine
stages read only its region of interest.

Taking every `step`-th pixel of every `step`-th row reads 1/step of the frame's memory
(whole cache lines of the kept rows), so a 20-megapixel frame costs about one read of a
tenth of it. The same blob rules as the fine stage run on the small view, so a frame
without a usable beacon is refused before any full-resolution work.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from server.outcomes import Refusal
from server.vision.binarize import Levels, estimate_levels, threshold
from server.vision.contour import BlobRules, PanelLook, find_beacon_blob
from shared_schemas import FailureReason


@dataclass(frozen=True)
class CoarseRules:
    """The subsampled view that both coarse stages read: this one (one panel) and
    `server.vision.beacons` (every panel). `RoiRules` and `beacons.CandidateRules` extend it,
    so its defaults are written once."""

    coarse_short_side_px: int = 480  # the view's short side is at least this (step = short side // it)
    min_contrast_dn: float = 20.0  # plateau - background below this: nothing stands out, no beacon

    def coarse_step(self, shape: tuple[int, ...]) -> int:
        """Subsampling step for a frame of `shape` (height, width): 1 for frames smaller than the view."""
        return max(1, min(shape[0], shape[1]) // self.coarse_short_side_px)


@dataclass(frozen=True)
class RoiRules(CoarseRules):
    margin_px: int = 12


@dataclass(frozen=True)
class Roi:
    """Where to look at full resolution: x0:x1, y0:y1 of the frame, and the frame's levels."""

    x0: int
    y0: int
    x1: int
    y1: int
    levels: Levels
    step: int


def coarse_view(pixels: np.ndarray, step: int) -> np.ndarray:
    """Every `step`-th pixel of every `step`-th row, plus the frame's last row and column.

    Without the last row and column the view would end up to step - 1 pixels short of the
    frame's far borders, and a panel just inside them would touch the view's border and be
    refused as cut off (found on a bench frame whose panel ended 8 px from the right edge).
    View pixel (row i, column j) is frame pixel (min(i step, height - 1), min(j step, width - 1))
    (`coarse_to_frame`).
    """
    height, width = pixels.shape
    grid = pixels[::step, ::step]
    extra_row, extra_col = int((height - 1) % step > 0), int((width - 1) % step > 0)
    small = np.empty((grid.shape[0] + extra_row, grid.shape[1] + extra_col), pixels.dtype)
    small[: grid.shape[0], : grid.shape[1]] = grid
    if extra_col:
        small[: grid.shape[0], -1] = pixels[::step, -1]
    if extra_row:
        small[-1, : grid.shape[1]] = pixels[-1, ::step]
        small[-1, -1] = pixels[-1, -1]
    return small


def coarse_to_frame(points: np.ndarray, step: int, shape: tuple[int, int]) -> np.ndarray:
    """Frame pixel coordinates (..., 2) x, y of `coarse_view` pixel coordinates (..., 2) x, y.

    Whole view pixels land exactly on the frame pixel they were read from: `step` times, except
    the view's extra last column and row, which are the frame's last (closer than `step`).
    """
    height, width = shape
    return np.minimum(np.asarray(points, dtype=float) * step, [width - 1, height - 1])


def find_roi(
    pixels: np.ndarray, rules: RoiRules = RoiRules(), blob_rules: BlobRules = BlobRules(), look: PanelLook = PanelLook()
) -> Roi | Refusal:
    """The beacon's region of interest in a full frame (height, width) uint8 (the panel's blob
    may be cut by the frame border: see `contour.find_beacon_blob`)."""
    height, width = pixels.shape
    step = rules.coarse_step(pixels.shape)
    small = coarse_view(pixels, step)
    levels = estimate_levels(small[::2])  # every other row: plenty for two percentiles, half the time
    if levels.contrast < rules.min_contrast_dn:
        return Refusal(
            FailureReason.no_beacon,
            f"nothing stands out of the background (contrast {levels.contrast:.0f} DN)",
        )
    # No blur here: it would spread a panel a few pixels from the frame edge onto the border
    # of the small view, and at this scale the panel stands hundreds of DN above the noise.
    blob = find_beacon_blob(threshold(small, levels), blob_rules, look)
    if isinstance(blob, Refusal):
        return blob
    x, y, w, h = blob.bounding_box
    margin = rules.margin_px + 2 * step
    return Roi(
        x0=max(0, x * step - margin),
        y0=max(0, y * step - margin),
        x1=min(width, (x + w) * step + margin),
        y1=min(height, (y + h) * step + margin),
        levels=levels,
        step=step,
    )
