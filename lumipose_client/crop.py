"""Send only the beacon's region: find the panel on a coarse view, cut a window around it.

A 20-megapixel luma plane is 20 MB on the wire; the window around a 0.174 m panel seen by
the Mi 8 front camera is about 3 MB at 1 m and a few hundred kilobytes at 2-3 m, and the
server's answer is the same (its fine stages only read that region).

Which window to send is the client's own rule, kept deliberately simple: the server finds the
panel again inside the window with its full checks, so the window only has to hold the whole
panel with a margin of background. The Android app's `BeaconWindow` is the same rule in Java,
with the same constants (shared_schemas/capture_protocol.json).

1. A coarse view: the mean of each square block, a `BLOCK_DIVISOR`-th of the short side.
2. A level half-way between the background (the view's median) and the bright plateau (its
   brightest block); nothing is cut when the two are less than `MIN_CONTRAST_DN` apart.
3. The bright region holding the brightest block (blocks at or above the level, 8-connected);
   the panel's extent is its bounding box grown by `EDGE_BLOCKS` blocks and `EDGE_PX` pixels a
   side (the blocks: the blurred edge and glow below the level; the pixels: the margin the
   server's region of interest keeps around the panel, `shared_schemas.windows.ROI_MARGIN_PX`).
4. A square window `WINDOW_PER_PANEL` times the extent's longer side around its centre,
   clipped to the frame.
5. The full frame's grey levels by the contract's coarse rule (`shared_schemas.windows`)
   go with the window (`crop.levels_dn`): the window's own histogram is mostly panel, and the
   server reads the window on the full frame's coarse grid with them, so its answer is the
   whole frame's (docs/contract.md, "Windows").
"""

from __future__ import annotations

import numpy as np

from shared_schemas import Crop, FrameFormat, FrameMeta
from shared_schemas.windows import ROI_MARGIN_PX, frame_levels

WINDOW_PER_PANEL = 1.0
BLOCK_DIVISOR = 240  # blocks across the short side of the coarse view
MIN_CONTRAST_DN = 20.0
EDGE_BLOCKS = 3  # the panel's extent: its bright region's box grown by this many blocks a side
EDGE_PX = ROI_MARGIN_PX  # and by the server's own margin around the panel, in pixels


def _block_means(pixels: np.ndarray, block: int) -> np.ndarray:
    """Mean of each whole block x block tile; the frame's last rows and columns that do not fill
    a tile (fewer than `block`) are left out of the view."""
    rows, cols = pixels.shape[0] // block, pixels.shape[1] // block
    tiles = pixels[: rows * block, : cols * block]
    row_sums = tiles.reshape(rows, block, cols * block).sum(axis=1, dtype=np.uint32)
    return row_sums.reshape(rows, cols, block).sum(axis=2) / (block * block)


def _region_of(seed: tuple[int, int], mask: np.ndarray) -> np.ndarray:
    """The 8-connected part of `mask` holding `seed`, grown one block ring at a time."""
    region = np.zeros_like(mask)
    region[seed] = True
    while True:
        grown = region.copy()
        grown[1:, :] |= region[:-1, :]
        grown[:-1, :] |= region[1:, :]
        grown[:, 1:] |= grown[:, :-1].copy()
        grown[:, :-1] |= grown[:, 1:].copy()
        grown &= mask
        if np.array_equal(grown, region):
            return region
        region = grown


def beacon_window(pixels: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1) of the window to send around the brightest panel, or None when nothing
    stands out of the background."""
    height, width = pixels.shape
    block = max(1, min(height, width) // BLOCK_DIVISOR)
    coarse = _block_means(pixels, block)
    background, plateau = float(np.median(coarse)), float(coarse.max())
    if plateau - background < MIN_CONTRAST_DN:
        return None
    row, col = np.unravel_index(np.argmax(coarse), coarse.shape)
    brightest = (int(row), int(col))
    region = _region_of(brightest, coarse >= (background + plateau) / 2)
    rows, cols = np.flatnonzero(region.any(axis=1)), np.flatnonzero(region.any(axis=0))
    # the panel's blurred edge and glow reach a few blocks below the level; a region at the view's
    # far edge may go on in the rows and columns the view left out
    margin = EDGE_BLOCKS * block + EDGE_PX
    left, top = cols[0] * block - margin, rows[0] * block - margin
    right = width if cols[-1] == coarse.shape[1] - 1 else (cols[-1] + 1) * block + margin
    bottom = height if rows[-1] == coarse.shape[0] - 1 else (rows[-1] + 1) * block + margin
    centre_x, centre_y = (left + right) / 2, (top + bottom) / 2
    half = WINDOW_PER_PANEL * max(right - left, bottom - top) / 2
    x0, y0 = max(0, int(centre_x - half)), max(0, int(centre_y - half))
    x1, y1 = min(width, int(np.ceil(centre_x + half))), min(height, int(np.ceil(centre_y + half)))
    return x0, y0, x1, y1


def crop_frame(
    pixels: np.ndarray, meta: FrameMeta, window: tuple[int, int, int, int] | None = None
) -> tuple[FrameMeta, bytes]:
    """The frame cut to `window` (x0, y0, x1, y1; default: the window around its panel), with the contract's
    `crop` block; the whole frame unchanged when no panel is found (the server then says why)."""
    window = window or beacon_window(pixels)
    if window is None:
        return meta, np.ascontiguousarray(pixels).tobytes()
    x0, y0, x1, y1 = window
    full_width, full_height = meta.full_size
    offset_x, offset_y = meta.full_offset
    # a window cut again keeps its frame's levels; a whole frame's are measured here
    levels = meta.crop.levels_dn if meta.crop else list(frame_levels(pixels))
    cropped = meta.model_copy(
        update={
            "width": x1 - x0,
            "height": y1 - y0,
            "row_stride": None,
            "format": FrameFormat.y8,
            "crop": Crop(
                x=offset_x + x0,
                y=offset_y + y0,
                full_width=full_width,
                full_height=full_height,
                levels_dn=levels,
            ),
        }
    )
    return FrameMeta.model_validate(cropped.model_dump(by_alias=True)), np.ascontiguousarray(
        pixels[y0:y1, x0:x1]
    ).tobytes()
