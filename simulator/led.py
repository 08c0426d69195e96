"""The rolling shutter's view of a modulated LED: one radiance multiplier per sensor row.

Row r of a frame starts its exposure at `start_s + r * row_time_s` (camera clock) and
integrates the light for `exposure_s`; its recorded value is the LED waveform averaged
over that window (contract, "Physics"). A 10 ms exposure spans more than one 8.4 ms
message and averages the code away; a 1/8000 s exposure keeps the stripes.
"""

from __future__ import annotations

import numpy as np

from server.vlc.codec import LedWaveform


def row_gains(waveform: LedWaveform, height: int, row_time_s: float, exposure_s: float,
              start_s: float = 0.0) -> np.ndarray:
    """Per-row multiplier (height,) float32 of the panel's full-on radiance.

    `row_time_s` = rolling_shutter_skew_s / (height - 1) of the delivered frame; `start_s`
    is the first row's exposure start on the camera clock (the frame's timestamp).
    """
    if height <= 0:
        raise ValueError(f"height must be positive, got {height}")
    if row_time_s < 0:
        raise ValueError(f"row_time_s must not be negative, got {row_time_s}")
    if exposure_s <= 0:
        raise ValueError(f"exposure_s must be positive, got {exposure_s}")
    starts = start_s + row_time_s * np.arange(height)
    return waveform.window_means(starts, exposure_s).astype(np.float32)
