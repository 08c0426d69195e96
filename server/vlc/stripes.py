"""What a striped region's rows say about the light that made them: blink frequency, duty, edge width.

A rolling shutter starts row r at t0 + r * row_time_s, so the mean of each row of a region lit
by one LED samples the LED's light in time, box-averaged over the row's exposure (docs/vlc.md).
For an LED keyed on and off (a square wave of frequency f and duty D):

- the rows between two rising edges span 1 / (f * row_time_s) rows: the half-level crossings of
  every rising and every falling edge, each placed to a fraction of a row by linear
  interpolation, are fitted by least squares as `offset + k * period_rows` (one period, one
  offset per edge kind, k the cycle index), which uses every edge of the region at once;
- the duty is the time from a rising to the next falling crossing over the period: at the half
  level, a box exposure delays both edges alike, so the duty is the LED's own;
- each edge spreads over exposure_s / row_time_s rows (the box smears a step into a ramp that
  long): its 10-90 % width is 0.8 of that ramp. What the camera adds (interpolation between
  rows in demosaicing and scaling, compression, a tone curve) widens or bends it.

`measure_stripes` reads a row signal (rows, means); `row_signal` takes it from a region of a frame
with the decoder's own row reader (`server.vlc.decoder.read_stripes`, one row per bin). The
region's edges are the caller's: a panel's mask, or a whole frame lit by a diffuser.

`turned_frame_problem` tells stripes across the rows from stripes along them: a frame turned by 90
degrees (a phone held sideways, a picture rotated before upload) shows its stripes as columns, and
its row means then read nonsense.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from server.vlc.decoder import PanelPixels, StripeRules, panel_pixels, read_stripes

# 10-90 % of a linear ramp: what a box exposure makes of a step
RAMP_10_90 = 0.8


@dataclass(frozen=True)
class StripeMeasureRules:
    # of the swing either side of half: noise within it makes no extra edge, and bright runs dimmed by
    # shading to 0.65 of the brightest still count (the real frame's bright level varies by 0.75 in light)
    hysteresis: float = 0.15
    min_swing_dn: float = 8.0  # between the dark and bright levels: below it, no stripes to measure
    min_edges: int = 3  # of each kind (rising, falling): a period needs more than two
    run_core: float = 0.5  # a run's level is the median of its middle half (its ends are ramps)


@dataclass(frozen=True)
class StripeMeasurement:
    """A square-wave blink read from the rows; every `*_sigma` is one standard deviation.

    Rows count the sensor's readout rows; crossings are row positions, pixel centres at integers.
    """

    period_rows: float
    period_rows_sigma: float
    frequency_hz: float
    frequency_hz_sigma: float
    duty: float  # time high / period at the half level, 0..1
    duty_sigma: float
    rise_width_rows: float  # 10-90 % width of the rising edges, their mean
    rise_width_rows_sigma: float
    fall_width_rows: float
    fall_width_rows_sigma: float
    predicted_width_rows: float  # 0.8 * exposure_s / row_time_s: a box exposure's 10-90 %
    dark_dn: float  # median level of the dark runs
    bright_dn: float
    rising_edges: int
    falling_edges: int
    rows: int  # rows read

    @property
    def edge_width_rows(self) -> float:
        """10-90 % width of all edges (rising and falling weighed by their counts)."""
        total = self.rising_edges + self.falling_edges
        return (self.rise_width_rows * self.rising_edges + self.fall_width_rows * self.falling_edges) / total


@dataclass(frozen=True)
class NoStripes:
    reason: str


def row_signal(
    pixels: np.ndarray,
    mask: np.ndarray,
    origin_yx: tuple[int, int],
    row_time_s: float,
    exposure_s: float,
    rules: StripeRules = StripeRules(),
) -> tuple[np.ndarray, np.ndarray] | None:
    """(rows, means) of the rows inside `mask` (bool, placed at `origin_yx` of `pixels`), each row
    its own sample: the decoder's reader (its edge margin and pixels per row) with one row per bin.
    None when fewer than `rules.min_samples` rows remain."""
    chip_s = 1.0 / rules.chip_rate_hz
    # bins of at most half a row round to one row each
    per_row = replace(rules, samples_per_chip=2 * max(1, int(np.ceil(chip_s / row_time_s))))
    observation = read_stripes(pixels, mask, origin_yx, 0.0, row_time_s, exposure_s, per_row)
    if observation is None:
        return None
    if observation.row_offsets_s.shape[1] != 1:
        raise AssertionError("read_stripes did not read one row per bin")
    rows = np.rint(observation.row_offsets_s[:, 0] / row_time_s).astype(np.int64)
    return rows, observation.values_dn.astype(np.float64)


def _runs(high: np.ndarray) -> list[tuple[int, int, bool]]:
    """(start, stop, is high) of each run of equal `high` (bool)."""
    change = np.flatnonzero(np.diff(high.astype(np.int8))) + 1
    bounds = np.concatenate([[0], change, [len(high)]])
    return [(int(a), int(b), bool(high[a])) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _crossing(values: np.ndarray, start: int, level: float) -> float:
    """Sub-row index where rising `values` first reach `level` after `start` (linear between samples)."""
    j = start + int(np.argmax(values[start:] >= level))
    if j == 0:
        return 0.0
    a, b = values[j - 1], values[j]
    return j - 1 + float((level - a) / (b - a)) if b > a else float(j)


def _edge(values: np.ndarray, start: int, dark: float, bright: float) -> tuple[float, float] | None:
    """(half-level crossing, 10-90 % width) of the rising edge from `dark` to `bright` that starts at
    sample `start` (below half); None when its 10 % or 90 % point is not inside."""
    swing = bright - dark
    half = _crossing(values, start, dark + 0.5 * swing)
    i = int(np.floor(half))
    # 10 %: the last sample below it before the half crossing; 90 %: the first sample above it after
    below = np.flatnonzero(values[: i + 1] <= dark + 0.1 * swing)
    if len(below) == 0:
        return None
    ten = _crossing(values, int(below[-1]), dark + 0.1 * swing)
    if not np.any(values[i:] >= dark + 0.9 * swing):
        return None
    ninety = _crossing(values, i, dark + 0.9 * swing)
    return half, ninety - ten


def _periodic_fit(rising: np.ndarray, falling: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Least squares of the crossings as offset (one per kind) + k * period; (params, covariance, residual
    RMS), params = (rising offset, falling offset, period)."""
    guess = float(np.median(np.diff(rising)))
    # each kind counts its cycles from its own first edge: at a duty near 0.5 a falling edge lies half a
    # period from any rising one, where rounding to the rising edges' cycles would pick either side
    k_rise = np.rint((rising - rising[0]) / guess)
    k_fall = np.rint((falling - falling[0]) / guess)
    design = np.zeros((len(rising) + len(falling), 3))
    design[: len(rising), 0] = 1.0
    design[len(rising) :, 1] = 1.0
    design[:, 2] = np.concatenate([k_rise, k_fall])
    target = np.concatenate([rising, falling])
    params, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ params
    dof = max(1, len(target) - 3)
    rms = float(np.sqrt(residual @ residual / dof))
    covariance = rms**2 * np.linalg.inv(design.T @ design)
    return params, covariance, rms


def _mean_sigma(values: list[float]) -> tuple[float, float]:
    array = np.asarray(values)
    sigma = float(array.std(ddof=1) / np.sqrt(len(array))) if len(array) > 1 else float("nan")
    return float(array.mean()), sigma


def measure_stripes(
    rows: np.ndarray,
    values_dn: np.ndarray,
    row_time_s: float,
    exposure_s: float,
    rules: StripeMeasureRules = StripeMeasureRules(),
) -> StripeMeasurement | NoStripes:
    """The blink of the light behind a row signal: `values_dn` (n,) the means of consecutive sensor
    rows `rows` (n,), row `r` starting its exposure `row_time_s` after row `r - 1`, for `exposure_s`.

    Levels: the rows split at the midpoint of their 2nd and 98th percentiles, with hysteresis
    (`rules.hysteresis` of the swing) so that noise near half makes no extra edge; every run's
    level is the median of its middle, and each edge is measured between the levels of its own two
    runs (a shading trend along the region does not move it).
    """
    if not row_time_s > 0:
        raise ValueError(f"row_time_s must be positive, got {row_time_s}")
    if not exposure_s > 0:
        raise ValueError(f"exposure_s must be positive, got {exposure_s}")
    rows = np.asarray(rows)
    values = np.asarray(values_dn, dtype=np.float64)
    if rows.shape != values.shape or rows.ndim != 1:
        raise ValueError(f"rows and values_dn must be equal 1-D arrays, got {rows.shape} and {values.shape}")
    if len(rows) > 1 and np.any(np.diff(rows) != 1):
        raise ValueError("rows must be consecutive")
    if len(values) < 4:
        return NoStripes(f"only {len(values)} rows")
    dark, bright = np.percentile(values, [2.0, 98.0])
    swing = bright - dark
    if swing < rules.min_swing_dn:
        return NoStripes(f"the rows vary by {swing:.1f} DN, less than {rules.min_swing_dn:g} DN: no stripes")
    # hysteresis: a row is high once above half + h, low once below half - h, else as the row before
    half, h = dark + 0.5 * swing, rules.hysteresis * swing
    state = np.empty(len(values), bool)
    current = bool(values[0] >= half)
    for i, v in enumerate(values):
        current = True if v >= half + h else False if v <= half - h else current
        state[i] = current
    runs = _runs(state)
    levels = []
    for start, stop, _ in runs:
        cut = int((stop - start) * (1 - rules.run_core) / 2)
        levels.append(float(np.median(values[start + cut : max(stop - cut, start + cut + 1)])))
    rising: list[float] = []  # half-level crossings, rows from the first row read
    falling: list[float] = []
    rise_widths: list[float] = []
    fall_widths: list[float] = []
    for n in range(1, len(runs)):
        _, before_stop, before_high = runs[n - 1]
        low, high = (levels[n], levels[n - 1]) if before_high else (levels[n - 1], levels[n])
        if high - low < rules.min_swing_dn:
            continue
        # a falling edge is a rising edge of the negated signal
        signal, lo, hi = (-values, -high, -low) if before_high else (values, low, high)
        # the hysteresis switches past half: the edge starts at the last row below half before that
        start = before_stop - 1
        while start > 0 and signal[start] > lo + 0.5 * (hi - lo):
            start -= 1
        edge = _edge(signal, start, lo, hi)
        if edge is None:
            continue
        (falling if before_high else rising).append(edge[0])
        (fall_widths if before_high else rise_widths).append(edge[1])
    if min(len(rising), len(falling)) < rules.min_edges:
        return NoStripes(f"{len(rising)} rising and {len(falling)} falling edges, fewer than {rules.min_edges} of each")
    rising_rows = rows[0] + np.array(rising)
    falling_rows = rows[0] + np.array(falling)
    params, covariance, _ = _periodic_fit(rising_rows, falling_rows)
    a_rise, a_fall, period = (float(p) for p in params)
    period_sigma = float(np.sqrt(covariance[2, 2]))
    high_rows = (a_fall - a_rise) % period
    # var(a_fall - a_rise) and its covariance with the period, for the duty's first-order error
    var_high = covariance[0, 0] + covariance[1, 1] - 2 * covariance[0, 1]
    cov_high_period = covariance[1, 2] - covariance[0, 2]
    duty = high_rows / period
    duty_var = (var_high - 2 * duty * cov_high_period + duty**2 * covariance[2, 2]) / period**2
    frequency = 1.0 / (period * row_time_s)
    rise_width, rise_sigma = _mean_sigma(rise_widths)
    fall_width, fall_sigma = _mean_sigma(fall_widths)
    dark_levels = [level for level, (_, _, high_run) in zip(levels, runs, strict=True) if not high_run]
    bright_levels = [level for level, (_, _, high_run) in zip(levels, runs, strict=True) if high_run]
    return StripeMeasurement(
        period_rows=period,
        period_rows_sigma=period_sigma,
        frequency_hz=frequency,
        frequency_hz_sigma=frequency * period_sigma / period,
        duty=duty,
        duty_sigma=float(np.sqrt(max(duty_var, 0.0))),
        rise_width_rows=rise_width,
        rise_width_rows_sigma=rise_sigma,
        fall_width_rows=fall_width,
        fall_width_rows_sigma=fall_sigma,
        predicted_width_rows=RAMP_10_90 * exposure_s / row_time_s,
        dark_dn=float(np.median(dark_levels)),
        bright_dn=float(np.median(bright_levels)),
        rising_edges=len(rising),
        falling_edges=len(falling),
        rows=len(values),
    )


def _profile_roughness(panel: PanelPixels, axis: int, trim: int) -> tuple[float, int]:
    """(sum of squared central differences, their count) of the means over a panel's shrunk mask (`panel.inner`)
    along `axis` (1: each row's mean, a profile down the rows; 0: each column's), without the `trim` first and
    last means (what is left there of the blurred outline)."""
    counts = panel.column_counts if axis == 0 else panel.row_counts
    used = np.flatnonzero(counts > 0)
    if len(used) < 2 * trim + 3:
        return 0.0, 0
    span = slice(used[0] + trim, used[-1] + 1 - trim)
    sums = panel.inside.sum(axis=0) if axis == 0 else panel.row_sums
    means = sums[span] / np.maximum(counts[span], 1)
    both = (counts[span][2:] > 0) & (counts[span][:-2] > 0)
    differences = (means[2:] - means[:-2])[both]
    return float(np.sum(differences**2)), int(both.sum())


@dataclass(frozen=True)
class StripeAxis:
    """How rough the profiles of a frame's panels are: the means of their columns (left to right) and
    of their rows (top to bottom), each a mean squared central difference, DN^2; `level_dn` the panels'
    mean level."""

    along_columns_dn2: float
    along_rows_dn2: float
    level_dn: float

    @property
    def ratio(self) -> float:
        """Columns' roughness over the rows', each floored at 0.01 DN^2 (a clean rendered panel: 1)."""
        return max(self.along_columns_dn2, 0.01) / max(self.along_rows_dn2, 0.01)


@dataclass(frozen=True)
class TurnedRules:
    # rendered ID frames (squares, rectangles both ways, circles at 0.8-3 m, 1/8000 and 1/2500 s) read
    # at most 0.97 (a panel inside one chip run, no stripes) and turned mostly 3-150 (docs/vlc.md, "A real
    # frame"); the real frame as one region 0.00002, turned 60 000
    max_ratio: float = 3.0
    # and the columns must step like stripes: their RMS central difference at least this of the level
    # (a turned frame's stripes of depth 0.3 give about 0.15), not a plain panel's faint texture
    min_relative_step: float = 0.03
    edge_margin_px: int = 3  # the masks shrunk by this (the stripe reader's margin) ...
    trim: int = 3  # ... and each profile's ends cut by this: what is left of the blurred outline
    # an LED keyed fully off cuts its light into separate bars, one stripe each: bars this many times as
    # tall as wide, at least `min_bars` of them side by side (crossed by one row), are stripes along the
    # columns (a correctly read panel's bars are stacked, each a row of stripes)
    bar_elongation: float = 3.0
    min_bars: int = 3


def stripe_axis(panels: list[PanelPixels], rules: TurnedRules = TurnedRules()) -> StripeAxis:
    """The profiles' roughness pooled over `panels` (`decoder.panel_pixels`, shrunk by `rules.edge_margin_px`).

    The rolling shutter's stripes run along the rows: the rows' means step at every edge while the
    columns' means, each over the same stripes, stay smooth, so the ratio is well below 1. A frame
    turned by 90 degrees shows its stripes along the columns: well above 1. Means, not pixels: the
    pixels' noise, alike in both directions, would pull both towards 1.
    """
    rough = [0.0, 0.0]
    counts = [0, 0]
    level_sum, level_count = 0.0, 0
    for panel in panels:
        if panel.edge_margin_px != rules.edge_margin_px:
            raise ValueError(f"a panel is shrunk by {panel.edge_margin_px} px, the rules say {rules.edge_margin_px}")
        inner_count = cv2.countNonZero(panel.inner.view(np.uint8))
        if inner_count == 0:
            continue
        level_sum += float(panel.inside[panel.inner].sum())
        level_count += inner_count
        for axis in (0, 1):  # both profiles sum the same values
            total, count = _profile_roughness(panel, axis, rules.trim)
            rough[axis] += total
            counts[axis] += count
    return StripeAxis(
        along_columns_dn2=rough[0] / max(counts[0], 1),
        along_rows_dn2=rough[1] / max(counts[1], 1),
        level_dn=level_sum / max(level_count, 1),
    )


def side_by_side_bars(boxes: list[tuple[int, int, int, int]], rules: TurnedRules = TurnedRules()) -> int:
    """The most blobs, of `boxes` (x, y, w, h), that are upright bars (h >= `bar_elongation` w) crossed
    by one row, none with another blob above or below it (a correctly read panel keyed fully off is a
    stack of bars, one per stripe; a narrow one's bars may be upright, but stacked)."""

    def stacked(box: tuple[int, int, int, int]) -> bool:
        x, y, w, h = box
        return any(
            ox < x + w and x < ox + ow and not (oy < y + h and y < oy + oh)
            for ox, oy, ow, oh in boxes
            if (ox, oy, ow, oh) != box
        )

    bars = [(y, y + h) for x, y, w, h in boxes if h >= rules.bar_elongation * w and not stacked((x, y, w, h))]
    return max((sum(top <= (a + b) / 2 < bottom for top, bottom in bars) for a, b in bars), default=0)


def _comb_region(pixels: np.ndarray, panel: PanelPixels, box: tuple[int, int, int, int]) -> PanelPixels:
    """`panel`, or its blob's whole `box` (x, y, w, h) of `pixels` when the mask spans under half the box's columns:
    a turned LED keyed fully off, whose mask is one upright bar of the comb the box holds (its own columns
    smooth, the box's stepping from bar to bar)."""
    x, y, w, h = box
    if 2 * np.count_nonzero(panel.mask.any(axis=0)) >= w:
        return panel
    return panel_pixels(pixels, np.ones((h, w), bool), (y, x), panel.edge_margin_px)


TURNED = "is the frame turned 90 degrees? Send it as the sensor reads it, rows in readout order"


def turned_frame_problem(
    pixels: np.ndarray,
    panels: list[PanelPixels],
    boxes: list[tuple[int, int, int, int]],
    rules: TurnedRules = TurnedRules(),
) -> str | None:
    """The sentence saying that the stripes of a frame's panels (`panels`: their pixels in their masks, shrunk by
    `rules.edge_margin_px`, `decoder.panel_pixels`; `boxes`: their bounding boxes (x, y, w, h)) run along the
    columns, as in a frame turned by 90 degrees, or None.

    Either the panels' columns step like stripes and their rows do not (`stripe_axis`), or the panels'
    rows are plain and `side_by_side_bars` finds at least `rules.min_bars`: an LED keyed fully off,
    its stripes along the columns, each a blob of its own."""
    axis = stripe_axis([_comb_region(pixels, panel, box) for panel, box in zip(panels, boxes, strict=True)], rules)
    step_dn = rules.min_relative_step * axis.level_dn
    if axis.ratio >= rules.max_ratio and np.sqrt(axis.along_columns_dn2) >= step_dn:
        return (
            f"stripes run along columns (the columns' means step {axis.ratio:.0f} times as much as the rows'): {TURNED}"
        )
    if np.sqrt(axis.along_rows_dn2) < step_dn:
        bars = side_by_side_bars(boxes, rules)
        if bars >= rules.min_bars:
            return f"stripes run along columns ({bars} upright bars side by side, none stacked): {TURNED}"
    return None
