"""How a window of a frame is read as the whole frame (docs/contract.md, "Windows").

A client may send only the window around the panel (`crop`). The server then reads it as it
reads the whole frame: on the full frame's coarse grid, with the full frame's grey levels,
which the client measures on the whole plane by the rule below and sends as `crop.levels_dn`
(a tight window's own histogram is mostly panel). The Android app's `FrameLevels` is the same
rule in Java (its constants come from shared_schemas/capture_protocol.json).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

COARSE_SHORT_SIDE_PX = 480  # the coarse view's short side is at least this: step = short side // it
PLATEAU_FRACTION = 2e-4  # the share of samples above the plateau: a panel on 0.02 % of the frame still sets it
ROI_MARGIN_PX = 12  # the server's region of interest reaches this (plus 2 steps) beyond the panel's coarse blob


def coarse_step(height: int, width: int, short_side_px: int = COARSE_SHORT_SIDE_PX) -> int:
    """Subsampling step of the coarse view of a (full) frame: 1 for frames smaller than the view."""
    return max(1, min(height, width) // short_side_px)


def coarse_view(pixels: np.ndarray, step: int, origin: tuple[int, int] = (0, 0)) -> np.ndarray:
    """Every `step`-th pixel of every `step`-th row from `origin` (column, row), plus the frame's
    last row and column.

    Without the last row and column the view would end up to step - 1 pixels short of the
    frame's far borders, and a panel just inside them would touch the view's border and be
    refused as cut off (found on a bench frame whose panel ended 8 px from the right edge).
    View pixel (row i, column j) is frame pixel (min(row0 + i step, height - 1), min(column0 + j step,
    width - 1)).
    """
    height, width = pixels.shape
    column0, row0 = origin
    grid = pixels[row0::step, column0::step]
    extra_row, extra_col = int((height - 1 - row0) % step > 0), int((width - 1 - column0) % step > 0)
    small = np.empty((grid.shape[0] + extra_row, grid.shape[1] + extra_col), pixels.dtype)
    small[: grid.shape[0], : grid.shape[1]] = grid
    if extra_col:
        small[: grid.shape[0], -1] = pixels[row0::step, -1]
    if extra_row:
        small[-1, : grid.shape[1]] = pixels[-1, column0::step]
        small[-1, -1] = pixels[-1, -1]
    return small


def histogram_levels(samples: np.ndarray, plateau_fraction: float = PLATEAU_FRACTION) -> tuple[float, float]:
    """(background, plateau) of 8-bit samples: the median and the (1 - plateau_fraction) quantile,
    as the smallest grey levels whose cumulative counts reach them (whole counts against float64
    fractions of the total, so that another language reproduces them exactly)."""
    return count_levels(grey_level_counts(samples), plateau_fraction)


def count_levels(counts: np.ndarray, plateau_fraction: float = PLATEAU_FRACTION) -> tuple[float, float]:
    """`histogram_levels` from the samples' counts (256,) per grey level (whole numbers, any dtype
    that holds them exactly: the server counts with OpenCV, several times faster than `np.bincount`)."""
    cumulative = np.cumsum(counts.astype(np.int64, copy=False))
    total = float(cumulative[-1])
    background = float(np.searchsorted(cumulative, 0.5 * total))
    plateau = float(np.searchsorted(cumulative, (1.0 - plateau_fraction) * total))
    return background, plateau


def grey_level_counts(samples: np.ndarray) -> np.ndarray:
    """Counts (256,) of each grey level of 8-bit `samples`."""
    return np.bincount(samples.ravel(), minlength=256)


def view_levels(
    small: np.ndarray, counts: Callable[[np.ndarray], np.ndarray] = grey_level_counts
) -> tuple[float, float]:
    """(background, plateau) from a coarse view: every other row is plenty for two quantiles.
    `counts`: how the grey levels are counted (the server's is OpenCV's, the same whole numbers)."""
    return count_levels(counts(small[::2]))


def frame_levels(pixels: np.ndarray) -> tuple[float, float]:
    """(background, plateau) of a whole frame (height, width) uint8, as `crop.levels_dn` carries them."""
    return view_levels(coarse_view(pixels, coarse_step(*pixels.shape)))
