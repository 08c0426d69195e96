"""A known tone curve undone before any stage reads the pixels (docs/contract.md, `tone_curve`).

The clipped-edge model assumes pixels proportional to light, as do the stripe decoder (a row's
mean = gain x the code's box average + offset) and the flattening of an ID frame's stripes (a row
divided by its gain): an `srgb` frame is mapped through the inverse sRGB curve first, for every path.

Mapping a whole 20-megapixel frame costs more than the whole pipeline, so a large frame is mapped
only where the stages read it: the full frame's coarse grid (every path's first look: levels and
blobs) and the box around everything that stands out of the background there, grown by more than
any stage reads beyond a coarse blob. The rest stays zero, and the stages never see it.
"""

from __future__ import annotations

import cv2
import numpy as np

from server.ingest import LumaFrame
from server.vision.roi import CoarseRules, FrameView, coarse_levels, coarse_to_frame
from shared_schemas import FrameMeta, ToneCurve
from shared_schemas.windows import coarse_view


def _srgb_decoded(v: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1: sRGB-encoded values in [0, 1] to linear light in [0, 1]."""
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


# 8 bits in, 8 bits out: the encoded pixels hold no more, and the stages read uint8 (the dark end
# loses steps it did not need: the panel's edge is measured between the background and the plateau).
SRGB_TO_LINEAR_DN = np.rint(255.0 * _srgb_decoded(np.arange(256) / 255.0)).astype(np.uint8)
SRGB_TO_LINEAR_DN.flags.writeable = False

# Coarse pixels this far above the background (of the contrast) bound the region mapped: below the
# lowest level any stage cuts at (the room candidates' 0.2; an ID frame's dark stripes are 0.3).
REGION_LEVEL_FRACTION = 0.1
# Beyond those pixels' box (and 2 coarse steps): more than any stage reads past a coarse blob (the
# region of interest's 12 px, a room panel's 48 px crop, the stripes' and the outline fit's few px).
REGION_MARGIN_PX = 64


def linearized(frame: LumaFrame) -> LumaFrame:
    """`frame` with a known tone curve undone, so that every stage reads light; other frames as they are.

    An `srgb` frame's pixels go through the inverse sRGB curve, and so do its client-measured
    levels (`crop.levels_dn`): the curve is monotone, so the levels of the mapped pixels are the
    mapped levels and a window still gives the whole frame's answer. The result says `linear`.
    """
    meta = frame.meta
    if meta.tone_curve is not ToneCurve.srgb:
        return frame
    crop = meta.crop
    if crop is not None and crop.levels_dn is not None:
        # levels may fall between grey levels (the contract's are floats): between the table's steps
        levels = np.interp(crop.levels_dn, np.arange(256), SRGB_TO_LINEAR_DN)
        crop = crop.model_copy(update={"levels_dn": [float(v) for v in levels]})
    meta = meta.model_copy(update={"tone_curve": ToneCurve.linear, "crop": crop})
    pixels = _mapped_where_read(frame.pixels, meta)
    pixels.flags.writeable = False
    return LumaFrame(pixels=pixels, meta=meta, camera=frame.camera)


def _mapped_where_read(pixels: np.ndarray, meta: FrameMeta) -> np.ndarray:
    """`pixels` through the table on the coarse grid and in the region the stages read; zero elsewhere.

    The grid is the contract's (`CoarseRules()`: the short side's 480 px, as clients measure windows'
    levels on it), which the one-panel and room stages read by default; rules with another grid
    would read zeros (tests/server/test_tone_curve.py compares every path with the whole plane mapped).
    """
    view = FrameView.of(meta)
    step, origin = view.grid(pixels.shape, CoarseRules())
    height, width = pixels.shape
    if step == 1:  # a frame no larger than the coarse view: every pixel is read
        return cv2.LUT(pixels, SRGB_TO_LINEAR_DN)
    x0, y0, x1, y1 = _region_read(pixels, view, step, origin)
    if (x1 - x0) * (y1 - y0) > width * height // 2:  # most of the frame: one pass over all of it is cheaper
        return cv2.LUT(pixels, SRGB_TO_LINEAR_DN)
    mapped = np.zeros((height, width), np.uint8)
    # what the coarse view reads (shared_schemas.windows.coarse_view): the grid, the grid rows' last
    # pixel and the last row (a whole column would touch every page of the frame)
    column0, row0 = origin
    mapped[row0::step, column0::step] = SRGB_TO_LINEAR_DN[pixels[row0::step, column0::step]]
    mapped[row0::step, -1] = SRGB_TO_LINEAR_DN[pixels[row0::step, -1]]
    mapped[-1] = SRGB_TO_LINEAR_DN[pixels[-1]]
    mapped[y0:y1, x0:x1] = cv2.LUT(pixels[y0:y1, x0:x1], SRGB_TO_LINEAR_DN)
    return mapped


def _region_read(pixels: np.ndarray, view: FrameView, step: int, origin: tuple[int, int]) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1): the box around every coarse pixel that stands out of the background, grown by
    more than any stage reads beyond it; empty when nothing stands out (every path stops at the coarse view)."""
    small = cv2.LUT(coarse_view(pixels, step, origin), SRGB_TO_LINEAR_DN)  # the coarse view the stages will see
    levels = view.levels or coarse_levels(small)
    lit = small > levels.background + REGION_LEVEL_FRACTION * levels.contrast
    if not lit.any():
        return 0, 0, 0, 0
    rows, columns = np.flatnonzero(lit.any(axis=1)), np.flatnonzero(lit.any(axis=0))
    box = np.array([[columns[0], rows[0]], [columns[-1], rows[-1]]])
    (first_x, first_y), (last_x, last_y) = coarse_to_frame(box, step, pixels.shape, origin)
    height, width = pixels.shape
    margin = REGION_MARGIN_PX + 2 * step
    return (
        max(0, int(first_x) - margin),
        max(0, int(first_y) - margin),
        min(width, int(last_x) + margin + 1),
        min(height, int(last_y) + margin + 1),
    )
