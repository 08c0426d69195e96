"""A striped panel made plain again, so that the one-panel pipeline can measure an ID frame.

In a short-exposure ID frame every sensor row of a panel carries one gain, the LED's
waveform averaged over that row's exposure (docs/vlc.md): the panel is a stack of bright and
dark stripes (0.3 to 1.0 of its level), and the pipeline's half-level threshold cuts it into
bars. The gain is the same for every pixel of one row of one panel, its edges included (an
edge pixel's partial cover is lit by the same LED in the same window), so dividing each
row's pixels (above the background) by that row's gain restores the plain panel. An LED that
switches (almost) off between chips leaves rows with no light to divide: those rows carry no
edge, and the panel's pixels there are blended from the lit rows above and below them (its
outline between two stripes is its neighbours'); a panel whose top or bottom lies in such dark
rows is not flattened (its outline there is unseen, no fix should come from it).

The gains come from the panel's own code, once its ID is read: the message's phase in this
frame is fitted to the interior rows' means (the mask shrunk by `edge_margin_px`, as the stripe
reader reads them) with a free level and depth, and the fitted waveform, box-averaged over each
row's exposure exactly as the sensor does, gives every row's gain, also the rows at the panel's
top and bottom edges, where no row mean can: there the PSF's partial cover and the gain are
mixed in the same pixels, and taking the nearest interior row's gain instead put the panel's
edge a pixel off whenever a chip boundary fell within those few rows (a 1200 x 300 mm panel at
2 m then moved its fix by 12 mm, against 1 mm with the true gains). Each panel has its own
code, so each is flattened with its own gains, only within its own mask grown by `grow_px`
(its blurred edge); the rest of the frame is left as it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from server.vlc.codec import CHIP_RATE_HZ, MESSAGE_CHIPS, LedWaveform, encode


@dataclass(frozen=True)
class FlattenRules:
    edge_margin_px: int = 3  # interior: the mask shrunk by this (the stripe reader's margin)
    min_pixels_per_row: int = 4  # interior pixels for a row's mean to count in the fit
    min_rows: int = 12  # interior rows for a fit at all
    grow_px: int = 6  # the mask grown by this is rescaled: the panel and its blurred edge
    phase_steps_per_chip: int = 64  # the phase grid: 1/64 chip = 6 us, a quarter of a row at 23 us
    max_residual: float = 0.15  # RMS of the fit's residuals over the fitted chip depth: beyond it, no flattening
    # of the full level: rows predicted darker carry too little light to rescale (their noise grows as 1 / gain,
    # 4x here) and are bridged from the lit rows around them; the LED's default low level, 0.3, is above it
    min_gain: float = 0.25


def flatten_stripes(
    pixels: np.ndarray,
    mask: np.ndarray,
    origin_yx: tuple[int, int],
    background_dn: float,
    beacon_id: int,
    row_time_s: float,
    exposure_s: float,
    rules: FlattenRules = FlattenRules(),
    chip_rate_hz: float = CHIP_RATE_HZ,
) -> str | None:
    """Rescale, in place, the rows of the panel with code `beacon_id` whose mask (bool) lies at
    `origin_yx` of `pixels` (uint8, writeable) to the panel's full level (the LED on for the whole
    exposure). None when done, else why not (then `pixels` is unchanged)."""
    y0, x0 = origin_yx
    h, w = mask.shape
    window = pixels[y0 : y0 + h, x0 : x0 + w]
    mask_u8 = mask.astype(np.uint8)
    interior = mask
    if rules.edge_margin_px > 0:
        size = 2 * rules.edge_margin_px + 1
        interior = cv2.erode(mask_u8, np.ones((size, size), np.uint8)).astype(bool)
    counts = interior.sum(axis=1)
    rows = np.flatnonzero(counts >= rules.min_pixels_per_row)
    if len(rows) < rules.min_rows:
        return f"only {len(rows)} rows inside the panel"
    values = window.astype(np.float32) - np.float32(background_dn)
    means = np.where(interior[rows], values[rows], 0.0).sum(axis=1) / counts[rows]
    weights = counts[rows] / counts[rows].sum()

    # the message's phase: least squares of the row means against the box-averaged code, free level and depth
    wave = LedWaveform(tuple(int(c) for c in encode(beacon_id)), chip_rate_hz=chip_rate_hz, low_level=0.0)
    steps = MESSAGE_CHIPS * rules.phase_steps_per_chip
    step_s = wave.period_s / steps
    table = wave.window_means(np.arange(steps) * step_s, exposure_s)
    shift = np.rint(rows * row_time_s / step_s).astype(np.int64)
    templates = table[(np.arange(steps)[:, None] + shift[None]) % steps]  # (phases, rows)
    centred = templates - (templates @ weights)[:, None]
    y = means - float(weights @ means)
    along = centred @ (weights * y)
    spread = (centred**2) @ weights
    depth = along / np.maximum(spread, 1e-12)
    residual = np.where(depth > 0, float(weights @ y**2) - along**2 / np.maximum(spread, 1e-12), np.inf)
    best = int(np.argmin(residual))
    if not depth[best] > 0 or not np.isfinite(residual[best]):
        return "no phase of the code fits the panel's rows"
    rms = float(np.sqrt(max(residual[best], 0.0)))
    if rms > rules.max_residual * depth[best]:
        return f"the code fits the panel's rows only to {rms / depth[best]:.2f} of its chip depth"
    offset = float(weights @ means - depth[best] * (templates[best] @ weights))

    # every row of the window, edges included: the fitted waveform over its exposure
    gain = offset + depth[best] * wave.window_means(best * step_s + np.arange(h) * row_time_s, exposure_s)
    full = offset + depth[best]
    if not full > 0:
        return "the fitted panel level is not positive"
    lit = gain >= rules.min_gain * full
    panel_rows = np.flatnonzero(mask.any(axis=1))
    for end, beyond in ((panel_rows[0], panel_rows[0] - 1), (panel_rows[-1], panel_rows[-1] + 1)):
        if 0 <= beyond < h and not lit[beyond]:  # the panel may go on in the dark rows past its first or last stripe
            side = "top" if end == panel_rows[0] else "bottom"
            return f"its {side} lies in a dark stripe of its code (the LED off between chips): its outline is unseen"
    scale = np.where(lit, full / np.maximum(gain, 1e-6), 1.0).astype(np.float32)
    grown = mask
    if rules.grow_px > 0:
        size = 2 * rules.grow_px + 1
        grown = cv2.dilate(mask_u8, np.ones((size, size), np.uint8)).astype(bool)
    rescaled = np.float32(background_dn) + values * scale[:, None]
    rescaled = _dark_rows_bridged(rescaled, lit)
    window[...] = np.where(grown, np.clip(np.rint(rescaled), 0, 255), window).astype(np.uint8)
    return None


def _dark_rows_bridged(rescaled: np.ndarray, lit: np.ndarray) -> np.ndarray:
    """`rescaled` (rows, columns) with every row that is not `lit` but lies between lit rows replaced by
    the linear blend of the nearest lit rows above and below: a dark row of an LED off between chips
    carries no edge, the panel's outline there is its neighbours'. Rows beyond the first or last lit
    row are left as they are."""
    rows = np.flatnonzero(lit)
    dark = np.flatnonzero(~lit)
    dark = dark[(dark > rows[0]) & (dark < rows[-1])] if len(rows) else dark[:0]
    if len(dark) == 0:
        return rescaled
    after = rows[np.searchsorted(rows, dark)]
    before = rows[np.searchsorted(rows, dark) - 1]
    share = ((dark - before) / (after - before)).astype(np.float32)[:, None]
    out = rescaled.copy()
    out[dark] = (1 - share) * rescaled[before] + share * rescaled[after]
    return out
