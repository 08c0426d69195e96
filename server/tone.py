"""A known tone curve undone before any stage reads the pixels (docs/contract.md, `tone_curve`).

The clipped-edge model assumes pixels proportional to light, as do the stripe decoder (a row's
mean = gain x the code's box average + offset) and the flattening of an ID frame's stripes (a row
divided by its gain): an `srgb` frame is mapped through the inverse sRGB curve first, for every
path. A whole 20-megapixel plane costs about as much as the pipeline (docs/performance.md); the
app sends windows, a fraction of a percent of it.
"""

from __future__ import annotations

import cv2
import numpy as np

from server.ingest import LumaFrame
from shared_schemas import ToneCurve


def _srgb_decoded(v: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1: sRGB-encoded values in [0, 1] to linear light in [0, 1]."""
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


# 8 bits in, 8 bits out: the encoded pixels hold no more, and the stages read uint8 (the dark end
# loses steps it did not need: the panel's edge is measured between the background and the plateau).
SRGB_TO_LINEAR_DN = np.rint(255.0 * _srgb_decoded(np.arange(256) / 255.0)).astype(np.uint8)
SRGB_TO_LINEAR_DN.flags.writeable = False


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
    pixels = cv2.LUT(frame.pixels, SRGB_TO_LINEAR_DN)
    pixels.flags.writeable = False
    return LumaFrame(pixels=pixels, meta=meta, camera=frame.camera)
