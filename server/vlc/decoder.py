"""Rolling-shutter stripe decoder: the beacon's ID from the rows of its image.

A rolling shutter starts row r of a frame at t0 + r * row_time_s (row_time_s =
rolling_shutter_skew_s / (height - 1)), so the rows across a panel sample the LED waveform
in time: a short exposure shows the chips as horizontal stripes (docs/vlc.md).

1. `read_stripes`: inside the panel's mask, shrunk by `edge_margin_px` so that the blurred
   edges do not count, each row's mean is one sample of the waveform averaged over the row's
   exposure; rows are grouped into bins of about a quarter chip. A row mean ignores where the
   panel lies along the row, so tilt and the panel's outline do not matter; uneven
   brightness along the rows averages out, and along the columns it is absorbed by a smooth
   (quadratic) trend fitted with every hypothesis.
2. `IdEvidence`: maximum likelihood over the candidate IDs. For every candidate, message phase
   and LED clock error, the predicted bin values (the code box-averaged over each row's
   exposure, exactly as the sensor does) are fitted with a free gain, offset and trend per
   frame; the residuals give a log-likelihood, the frames' log-likelihoods add (their
   relative phase is known from their timestamps), and the posterior of each ID sums over
   phase and clock error. A frame holding less than one message leaves several IDs
   plausible; the frames that follow, at other phases, settle it.
3. Hypotheses: with a map, its IDs and "none of them" (the stripes are of a panel from
   elsewhere, or of two panels' stripes read as one); without, each of the 256 IDs. Every code
   is fitted either way: "none" is as likely as the best-fitting code outside the map (its ID is
   whatever it is, not one of 252 equally likely: a neighbouring room's panel may differ from a
   map ID in a single bit, so the worst case is the honest one). The decision is confident only
   when a map ID's posterior reaches `confident_posterior`; "none" winning is reported with the
   code it read, never confident.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import cv2
import numpy as np

from server.vlc.codec import CHIP_RATE_HZ, MAX_ID, MESSAGE_CHIPS, LedWaveform, encode


@dataclass(frozen=True)
class StripeRules:
    edge_margin_px: int = 3
    min_pixels_per_row: int = 4
    samples_per_chip: int = 4
    rows_per_sample_max: int = 6  # rows read per bin (evenly spread); more only cost time
    trend_degree: int = 2  # smooth brightness change along the columns
    phase_steps_per_chip: int = 8
    lut_steps_per_chip: int = 64
    max_clock_error_ppm: float = 100.0  # LED crystal against the phone's clock
    clock_steps_per_chip: int = 4  # clock-error grid: phase slip per step over the frames' span
    confident_posterior: float = 0.99
    # the fitted modulation depth, gain / (the fitted level of a 1 chip): an LED's is 0.3 to 1.0 (0.7 by default,
    # 1.0 off between chips); a ripple of a few per cent (a long exposure, flicker, banding) is no reading
    min_depth: float = 0.2
    min_samples: int = 6
    chip_rate_hz: float = CHIP_RATE_HZ
    # longer ID exposures are refused before decoding (server.vlc.capture.id_frame_problem): beyond one
    # chip the box average smears neighbouring chips together
    max_exposure_chips: float = 1.0


@dataclass(frozen=True)
class StripeObservation:
    """The stripe signal of one panel in one frame.

    `row_offsets_s` (n, m): exposure start of the m rows read for each of the n bins,
    relative to `timestamp_s` (the frame's first-row exposure start, camera clock).
    """

    timestamp_s: float
    exposure_s: float
    row_offsets_s: np.ndarray
    values_dn: np.ndarray  # (n,) bin means
    sigma_dn: np.ndarray  # (n,) standard error of each bin mean from the pixels' spread
    position: np.ndarray  # (n,) bin row, scaled to [-1, 1] over the panel (trend regressor)
    chips_seen: float  # time the panel's rows span, in chips

    @property
    def nbytes(self) -> int:
        """Memory held by its arrays."""
        return self.row_offsets_s.nbytes + self.values_dn.nbytes + self.sigma_dn.nbytes + self.position.nbytes

    @property
    def samples(self) -> int:
        return len(self.values_dn)


ALL_IDS = tuple(range(MAX_ID + 1))


@dataclass(frozen=True)
class IdDecision:
    # the best hypothesis's ID, confident or not: a map ID, or (`in_map` False) when "none of the map's"
    # wins, the best-fitting code outside the map; None with no usable stripes
    beacon_id: int | None
    confidence: float  # the posterior of its hypothesis (for an ID outside the map: of "none")
    confident: bool  # never for an ID outside the map
    frames: int
    chips_seen: float  # over all frames combined (with overlaps)
    message: str
    in_map: bool = True  # False: the stripes read as `beacon_id`, which is none of the map's


def row_time_s(skew_s: float, height: int) -> float:
    """Time between the exposure starts of neighbouring rows (contract: skew spans first to last row)."""
    if height < 2:
        raise ValueError(f"height must be at least 2 rows, got {height}")
    if not skew_s > 0:
        raise ValueError(f"rolling_shutter_skew_s must be positive to read stripes, got {skew_s}")
    return skew_s / (height - 1)


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class PanelPixels:
    """A panel's pixels inside its mask shrunk by `edge_margin_px` (its blurred outline left out), worked out once
    for what reads them: the row reader (`read_panel_stripes`) and the turned-frame test (`stripes.stripe_axis`)."""

    origin_yx: tuple[int, int]  # of the mask in the frame
    mask: np.ndarray  # (h, w) bool, as given
    edge_margin_px: int
    inner: np.ndarray  # (h, w) bool: `mask` eroded by a (2 edge_margin_px + 1) square
    inside: np.ndarray  # (h, w) float32: the pixels inside `inner`, 0 elsewhere
    row_counts: np.ndarray  # (h,) int64: `inner`'s pixels per row
    column_counts: np.ndarray  # (w,) int64: per column
    row_sums: np.ndarray  # (h,) float32: `inside` summed per row (numpy's float32 sums)


def _counts(inner: np.ndarray, axis: int) -> np.ndarray:
    """`inner.sum(axis=axis)` (bool, 2-D), the same int64 counts, by OpenCV (~6x faster than numpy's bool sums)."""
    return cv2.reduce(inner.view(np.uint8), axis, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel().astype(np.int64)


def panel_pixels(pixels: np.ndarray, mask: np.ndarray, origin_yx: tuple[int, int], edge_margin_px: int) -> PanelPixels:
    """The `PanelPixels` of `mask` (bool, placed at `origin_yx` of `pixels`), shrunk by `edge_margin_px`."""
    y0, x0 = origin_yx
    mask = np.ascontiguousarray(mask, dtype=bool)  # viewed as uint8 for OpenCV
    h, w = mask.shape
    inner = mask
    if edge_margin_px > 0:
        size = 2 * edge_margin_px + 1
        inner = cv2.erode(mask.view(np.uint8), np.ones((size, size), np.uint8)).view(bool)
    inside = pixels[y0 : y0 + h, x0 : x0 + w].astype(np.float32)
    inside[~inner] = 0.0
    return PanelPixels(
        origin_yx=(y0, x0),
        mask=mask,
        edge_margin_px=edge_margin_px,
        inner=inner,
        inside=inside,
        row_counts=_counts(inner, 1),
        column_counts=_counts(inner, 0),
        row_sums=inside.sum(axis=1),
    )


def read_stripes(
    pixels: np.ndarray,
    mask: np.ndarray,
    origin_yx: tuple[int, int],
    timestamp_s: float,
    row_time: float,
    exposure_s: float,
    rules: StripeRules = StripeRules(),
) -> StripeObservation | None:
    """Bin means of the rows inside `mask` (bool, placed at `origin_yx` of `pixels`), or None.

    None when fewer than `min_samples` bins remain after shrinking the mask.
    """
    panel = panel_pixels(pixels, mask, origin_yx, rules.edge_margin_px)
    return read_panel_stripes(panel, timestamp_s, row_time, exposure_s, rules)


def read_panel_stripes(
    panel: PanelPixels, timestamp_s: float, row_time: float, exposure_s: float, rules: StripeRules = StripeRules()
) -> StripeObservation | None:
    """`read_stripes` of a panel's pixels already shrunk (`panel_pixels`, by `rules.edge_margin_px`)."""
    if exposure_s is None or not exposure_s > 0:
        raise ValueError(f"exposure_s must be positive to read stripes, got {exposure_s}")
    if panel.edge_margin_px != rules.edge_margin_px:
        raise ValueError(f"the panel is shrunk by {panel.edge_margin_px} px, the rules say {rules.edge_margin_px}")
    y0, _ = panel.origin_yx
    counts = panel.row_counts
    rows = np.flatnonzero(counts >= rules.min_pixels_per_row)
    if len(rows) == 0:
        return None
    first, last = rows[0], rows[-1]
    rows = np.arange(first, last + 1)  # the panel is convex: one run of rows
    counts = np.maximum(counts[rows], 1)
    # the pixels inside (0 outside) as float32, summed per row: float32 sums, in numpy's order
    sums = panel.row_sums[first : last + 1]
    squares = np.square(panel.inside[first : last + 1]).sum(axis=1)
    means = sums / counts
    variances = np.maximum(squares / counts - means**2, 1.0) / counts  # of each row mean
    chip_s = 1.0 / rules.chip_rate_hz
    per_bin = max(1, int(round(chip_s / rules.samples_per_chip / row_time)))
    bins = len(rows) // per_bin
    if bins < rules.min_samples:
        return None
    used = bins * per_bin
    values = means[:used].reshape(bins, per_bin).mean(axis=1)
    sigma = np.sqrt(variances[:used].reshape(bins, per_bin).mean(axis=1) / per_bin)
    pick = np.unique(np.linspace(0, per_bin - 1, min(per_bin, rules.rows_per_sample_max)).round().astype(int))
    absolute_rows = (y0 + rows[:used]).reshape(bins, per_bin)[:, pick]
    centre = absolute_rows.mean(axis=1)
    position = (centre - centre.mean()) / max(1.0, (centre.max() - centre.min()) / 2)
    return StripeObservation(
        timestamp_s=float(timestamp_s),
        exposure_s=float(exposure_s),
        row_offsets_s=absolute_rows * row_time,
        values_dn=values,
        sigma_dn=sigma,
        position=position,
        chips_seen=float((used * row_time + exposure_s) / chip_s),
    )


@lru_cache(maxsize=16)
def _lookup(candidates: tuple[int, ...], exposure_s: float, steps_per_chip: int, chip_rate_hz: float) -> np.ndarray:
    """(MESSAGE_CHIPS * steps, C) each candidate's 0/1 code box-averaged over `exposure_s`, one row a time
    step: a bin's rows are gathered as whole rows of all candidates."""
    chip_s = 1.0 / chip_rate_hz
    times = np.arange(MESSAGE_CHIPS * steps_per_chip) * chip_s / steps_per_chip
    table = [
        LedWaveform(tuple(int(c) for c in encode(i)), chip_rate_hz=chip_rate_hz, low_level=0.0).window_means(
            times, exposure_s
        )
        for i in candidates
    ]
    return np.ascontiguousarray(np.array(table, dtype=np.float32).T)


# phases x bins fitted at once: a block's arrays (about 1 MB) stay in cache and are reused; fresh 10-50 MB arrays
# for all phases at once cost more in page faults than the sums themselves
BLOCK_PHASE_BINS = 400
# a hypothesis whose log-likelihood lies this far below the best one's weighs exactly nothing: exp() of less than
# -745.13 is 0 in float64 (`decide` sums exp(log-likelihood - best))
NEGLIGIBLE_LOG_LIKELIHOOD = 750.0
# the bound's allowance for rounding (relative): the reference's sums of ~50 terms err by ~1e-14 of their size
ROUNDING_SLACK = 1e-9
# of the sums' absolute size: the bound's transforms are float32 (half the time); 168 points of entries <= 1 err
# by ~6e-8 x log2(168) x sqrt(168) = 6e-6 of it at most (3e-7 seen on the bench's frames)
FFT_SLACK = 1e-4


@lru_cache(maxsize=4)
def _table_spectrum(key: tuple, patterns: tuple[tuple[int, ...], ...], stride: int, power: int) -> np.ndarray:
    """(frequencies, patterns x stride, C): for each of `patterns` the table `_lookup(*key)` averaged over the
    rows the pattern's entries on (row s: the mean of rows s + pattern, float64), to the `power`, split into
    `stride` interleaved sequences (rows r, r + stride, ...) and transformed along them (a frame's bins
    share a few patterns, the frames of one camera the same: ~17 MB for six)."""
    table = _lookup(*key).astype(np.float64)
    steps, count = table.shape
    spectra = []
    for pattern in patterns:
        averaged = np.mean([np.roll(table, -k, axis=0) for k in pattern], axis=0) ** power
        spectra.append(np.fft.rfft(averaged.reshape(steps // stride, stride, count), axis=0).astype(np.complex64))
    return np.concatenate(spectra, axis=1)


def _correlations(sums: np.ndarray, spectrum: np.ndarray) -> np.ndarray:
    """(frequencies, K, C) the spectra of sum_s sums[k, t, s] table_t[s + stride p, c] over the phases p and the
    tables t (`sums`: (K, tables, steps); `spectrum`: the tables', `_table_spectrum`): per interleaved sequence
    a correlation, summed over the sequences and the tables."""
    count, tables, steps = sums.shape
    stride = spectrum.shape[1] // tables
    weights = np.fft.rfft(sums.reshape(count, tables, steps // stride, stride), axis=2).astype(np.complex64)
    weights = np.ascontiguousarray(weights.transpose(2, 0, 1, 3)).reshape(-1, count, tables * stride)
    if count == 1:  # one row: numpy's complex vector-matrix path is ~100x slower than two rows' matrix product
        return np.matmul(np.concatenate([weights.conj(), np.zeros_like(weights)], axis=1), spectrum)[:, :1]
    return np.matmul(weights.conj(), spectrum)


@lru_cache(maxsize=16)
def _steepest(key: tuple) -> float:
    """The largest change between neighbouring rows of the table `_lookup(*key)` (cyclic)."""
    table = _lookup(*key).astype(np.float64)
    return float(np.abs(np.diff(table, axis=0, append=table[:1])).max())


class _FrameFit:
    """One frame's fits of every hypothesis (C codes x phases x clock errors), the exact ones made on demand.

    `explained[c, p, e]`: the part of the whitened, trend-free bin values that code c at phase p and clock
    error e explains (0 for an implausible fit: too shallow); exact for the blocks of phases in `exact`
    (`BLOCK_PHASE_BINS`), each block fitted by the same calls whichever blocks are asked for (so to the last
    bit what fitting all of them gives, `_frame_log_likelihood`), elsewhere an upper bound (`_bound`). The
    frame's scale needs its best fit: the blocks are fitted best bound first until no bound is above the
    best exact value (`log_likelihood`); `_total_log_likelihood` asks for the blocks that can weigh."""

    def __init__(
        self,
        obs: StripeObservation,
        reference_s: float,
        candidates: tuple[int, ...],
        clock_errors_ppm: np.ndarray,
        rules: StripeRules,
    ) -> None:
        self.observation, self.reference_s, self.rules = obs, reference_s, rules
        self.clock_errors_ppm = clock_errors_ppm
        self._lut_key = (candidates, round(obs.exposure_s, 9), rules.lut_steps_per_chip, rules.chip_rate_hz)
        self.lut = _lookup(*self._lut_key)
        steps, count = self.lut.shape
        chip_s = 1.0 / rules.chip_rate_hz
        period_s = MESSAGE_CHIPS * chip_s
        phases_s = np.arange(MESSAGE_CHIPS * rules.phase_steps_per_chip) * chip_s / rules.phase_steps_per_chip
        # trend basis, whitened by each bin's noise; its orthonormal complement removes gain-free parts
        self.weights = 1.0 / obs.sigma_dn
        basis = np.vander(obs.position, rules.trend_degree + 1) * self.weights[:, None]
        self.q, _ = np.linalg.qr(basis)
        y = obs.values_dn * self.weights
        self.y_p = y - self.q @ (self.q.T @ y)
        self.level = float(np.mean(obs.values_dn))
        self.total = float(self.y_p @ self.y_p)
        self.dof = max(1, obs.samples - rules.trend_degree - 2)
        bins, rows = obs.row_offsets_s.shape
        phases = len(phases_s)
        # blocks of one size, a divisor of the phases; in each, every hypothesis's template is a row fitted by the
        # same calls as when all were fitted at once: the same numbers to the last bit (codes that fit alike tie
        # exactly, and the first in ID order is named)
        self.block = max(
            d for d in range(1, phases + 1) if phases % d == 0 and (d == 1 or d * bins <= BLOCK_PHASE_BINS)
        )
        self.indices = []  # per clock error: (phases, n, m) each row's table entry, kept for the fits asked later
        kept = np.int16 if 2 * steps < np.iinfo(np.int16).max else np.int64  # a quarter of the memory; sums of two fit
        for ppm in clock_errors_ppm:
            rate = 1.0 + ppm * 1e-6
            times = (obs.timestamp_s - reference_s + obs.row_offsets_s) * rate  # (n, m)
            index = ((phases_s[:, None, None] + times[None]) % period_s / period_s * steps).astype(np.int64) % steps
            self.indices.append(index.astype(kept))
        self.explained = np.empty((count, phases, len(clock_errors_ppm)))  # C order: decide() sums along phases
        for e, index in enumerate(self.indices):
            self.explained[:, :, e] = self._bound(index).T
        self.exact = np.zeros((phases // self.block, len(clock_errors_ppm)), bool)
        self._buffers: tuple[np.ndarray, ...] | None = None
        self._scale: float | None = None
        if not np.isfinite(self.explained).all():  # no bound (a bin without noise): every fit made
            self.fit(np.ones_like(self.exact))

    def _bound(self, index: np.ndarray) -> np.ndarray:
        """(phases, C) an upper bound of each fit's explained part (`index`: one clock error's table entries).

        T~, the whitened template of each code and phase, reads each row at its entry at the first phase moved
        by the phase (`stride` entries a phase): the reference's own entries but where rounding moved one by an
        entry. With T the reference's template and D >= |T - T~| (k entries off: |dT| <= k x the table's
        steepest step; and its float32 sums), by Cauchy-Schwarz explained = (P T . y)^2 / |P T|^2 <=
        ((|P T~ . y| + D |y|) / (|P T~| - D))^2 (P: the trend-free part; y is trend-free), and never above
        |y|^2; every term with an allowance for its rounding. T~'s sums over the bins (T~ . y, T~ . q_k,
        |T~|^2) are correlations of a table with the bins' weights at their entries: every phase at once by
        FFT."""
        steps, count = self.lut.shape
        phases, bins, rows = index.shape
        ceiling = self.total * (1.0 + ROUNDING_SLACK)  # Cauchy-Schwarz: no fit explains more than all of y
        if steps % phases:
            return np.full((phases, count), ceiling)
        stride = steps // phases
        first = index[0, :, 0]
        # each bin's rows' entries from its first row's at the first phase: a few patterns among the bins
        offsets = (index[0] - first[:, None] + steps // 2) % steps - steps // 2
        patterns, kinds = np.unique(offsets, axis=0, return_inverse=True)
        # each row's entry against T~'s (its first phase's moved by the phase), in entries (cyclic), and the
        # reference's float32 sums (~7 ulp of a value <= 1)
        moved = first[None, :, None] + stride * np.arange(phases)[:, None, None] + offsets
        miss = _steepest(self._lut_key) * np.abs((index - moved + steps // 2) % steps - steps // 2).mean(axis=2)
        w = self.weights
        spread = np.sqrt(((miss + 2e-6) * w) ** 2 @ np.ones(bins))  # D per phase
        vectors = np.vstack([w * self.y_p, (w[:, None] * self.q).T, w**2])  # (2 + k, n): y, q_k and |T~|^2
        # the sums over the bins as correlations of a table with the vectors' weights at the bins' entries: the
        # linear ones of the table itself at each row's entry, |T~|^2 of each bin's pattern's averaged table
        linear = np.zeros((len(vectors) - 1, 1, steps))
        for k, vector in enumerate(vectors[:-1]):
            np.add.at(linear[k, 0], index[0].ravel(), np.repeat(vector / rows, rows))
        square = np.zeros((1, len(patterns), steps))
        np.add.at(square[0], (kinds.ravel(), first), vectors[-1])
        spectrum = np.concatenate(
            [
                _correlations(linear, _table_spectrum(self._lut_key, ((0,),), stride, 1)),
                _correlations(square, _table_spectrum(self._lut_key, tuple(map(tuple, patterns.tolist())), stride, 2)),
            ],
            axis=1,
        )
        sums_fft = np.fft.irfft(spectrum, n=phases, axis=0).astype(np.float64)  # (phases, 2 + k, C)
        linear, square = sums_fft[:, :-1], sums_fft[:, -1]
        # the transforms' rounding: far below this share of each vector's absolute sum (table entries <= 1)
        error = FFT_SLACK * np.abs(vectors).sum(axis=1)
        trend_of_y = np.abs(self.q.T @ self.y_p)  # ~0: y is trend-free up to rounding
        dots = np.abs(linear[:, 1:]) + error[1:-1, None]  # >= |T~ . q_k|
        along = np.abs(linear[:, 0]) + error[0] + np.einsum("pkc,k->pc", dots, trend_of_y)  # >= |P T~ . y|
        trend = np.einsum("pkc,pkc->pc", dots, dots)  # >= |T~'s trend|^2
        perp = np.sqrt(np.maximum(square - error[-1] - trend - 1e-10 * square, 0.0))  # <= |P T~|
        size = np.sqrt(np.maximum(square, 0.0) + error[-1])  # >= |T~|
        y_size = float(np.sqrt(self.total))
        numerator = along + (spread[:, None] + ROUNDING_SLACK * size) * y_size
        denominator = perp - spread[:, None] - ROUNDING_SLACK * size
        with np.errstate(divide="ignore", invalid="ignore"):
            fitted = np.where(denominator > 0, (numerator / denominator) ** 2 * (1.0 + ROUNDING_SLACK), ceiling)
        return np.minimum(fitted, ceiling)

    def fit(self, blocks: np.ndarray) -> None:
        """The exact fits of the blocks (phase block, clock error) marked in `blocks` (bool, as `exact`)."""
        rules, lut, weights, q, y_p = self.rules, self.lut, self.weights, self.q, self.y_p
        steps, count = lut.shape
        block = self.block
        if self._buffers is None:
            bins, rows = self.indices[0].shape[1:]
            raw = np.empty((block, bins, count), np.float32)  # gathered as whole rows of the table
            templates = np.empty((block, count, bins))
            # codes (phases, C, n): each bin's share of a 1 chip
            self._buffers = (raw, np.empty_like(raw), np.empty((block, count, bins), np.float32), templates,
                             np.empty_like(templates))  # fmt: skip
        raw, row, codes, templates, trend = self._buffers
        rows = self.indices[0].shape[2]
        for b, e in zip(*np.nonzero(blocks & ~self.exact), strict=True):
            index = self.indices[e]
            start = b * block
            # each bin's mean over its rows, summed in order as numpy's mean sums them; the indices are in range
            # already: "clip" writes straight into `out` ("raise" buffers it, a copy more)
            np.take(lut, index[start : start + block, :, 0], axis=0, out=raw, mode="clip")
            for j in range(1, rows):
                raw += np.take(lut, index[start : start + block, :, j], axis=0, out=row, mode="clip")
            raw /= np.float32(rows)
            codes[...] = raw.transpose(0, 2, 1)
            np.multiply(codes, weights, out=templates)
            templates -= np.matmul(np.matmul(templates, q), q.T, out=trend)  # the trend-free part
            norm = np.einsum("pcn,pcn->pc", templates, templates)
            along = templates @ y_p
            # a hypothesis must explain stripes as deep as an LED's code makes them, whatever its depth: the
            # frame's own levels give it (the dark level = the panel's mean less the gain times the code's
            # mean share; depth = gain / (dark level + gain), the background counted as light: a shade low)
            gain = along / np.maximum(norm, 1e-12)
            bright = self.level + gain * (1.0 - codes.mean(axis=-1))
            plausible = (gain >= rules.min_depth * bright) & (norm > 1e-12)
            explained = np.where(plausible, along**2 / np.maximum(norm, 1e-12), 0.0)
            self.explained[:, start : start + block, e] = explained.T
            self.exact[b, e] = True

    def log_likelihood(self) -> np.ndarray:
        """(C, phases, clock errors) log-likelihood relative to the frame's best fit: exact in the `exact` blocks,
        elsewhere an upper bound. The best fit is fitted first (best bound first, until no bound is above it)."""
        if self._scale is None:
            per_block = self.explained.reshape(self.explained.shape[0], -1, self.block, self.exact.shape[1])
            bounds = per_block.max(axis=(0, 2))  # (blocks, clock errors)
            best = float(bounds[self.exact].max(initial=-np.inf))
            while True:
                left = ~self.exact & (bounds >= best)
                if not left.any():
                    break
                top = np.zeros_like(left)
                b, e = np.unravel_index(np.argmax(np.where(left, bounds, -np.inf)), left.shape)
                top[b, e] = True
                self.fit(top)
                # a fit changes its own block only: the best of the exact ones is the old best or in it
                best = float(np.maximum(best, per_block[:, b, :, e].max()))
            result = self.total - self.explained
            self._scale = max(1.0, float(result.min()) / self.dof)  # residuals beyond the pixel noise: the model's own
        return -0.5 * (self.total - self.explained) / self._scale

    def exact_phases(self) -> np.ndarray:
        """(phases, clock errors) True where `log_likelihood` is exact."""
        return np.repeat(self.exact, self.block, axis=0)

    def fit_phases(self, phases: np.ndarray) -> None:
        """The exact fits of the blocks holding the phases marked in `phases` (phases, clock errors)."""
        self.fit(np.asarray(phases.reshape(self.exact.shape[0], self.block, -1).any(axis=1)))

    def release(self) -> None:
        """Drop the fits' working arrays (a few MB), kept from one block to the next."""
        self._buffers = None


def _frame_log_likelihood(
    obs: StripeObservation,
    reference_s: float,
    candidates: tuple[int, ...],
    clock_errors_ppm: np.ndarray,
    rules: StripeRules,
) -> np.ndarray:
    """(C, phases, clock errors) log-likelihood of one frame, every hypothesis fitted; relative to its best fit."""
    fit = _FrameFit(obs, reference_s, candidates, clock_errors_ppm, rules)
    fit.fit(np.ones_like(fit.exact))
    return fit.log_likelihood()


def _total_log_likelihood(fits: list[_FrameFit]) -> np.ndarray:
    """(C, phases, clock errors) the frames' log-likelihoods summed, exact wherever exp(it - its maximum) is
    not 0 (as if every hypothesis were fitted in every frame): a phase that some frame holds only as a bound is
    fitted in every frame (its block) unless its bounds sum to `NEGLIGIBLE_LOG_LIKELIHOOD` below the best exact
    total, where the exact value, lower still, weighs exactly nothing too. (Each frame has its own blocks.)"""
    while True:
        total: np.ndarray = np.zeros(())  # broadcasts to the first frame's shape
        for fit in fits:
            total = total + fit.log_likelihood()
        exact = np.logical_and.reduce([fit.exact_phases() for fit in fits])  # (phases, clock errors)
        best = total.max(axis=0)  # (phases, clock errors) over the codes
        # nothing exact in every frame yet: the best phases first
        floor = float(best[exact].max()) - NEGLIGIBLE_LOG_LIKELIHOOD if exact.any() else float(best.max())
        needed = ~exact & (best >= floor)
        if not needed.any():
            for fit in fits:
                fit.release()
            return total
        for fit in fits:
            fit.fit_phases(needed)


def _normalised(log_weights: np.ndarray) -> np.ndarray:
    weights = np.exp(log_weights - log_weights.max())
    return weights / weights.sum()


@dataclass
class IdEvidence:
    """ID evidence of one panel over consecutive frames of one device (mutable accumulator).

    Hypotheses: with `map_ids`, each of them (sharing 1 - `none_prior` of the prior) and "none of
    them" (`none_prior`, as likely as the best-fitting code outside the map); without, the 256
    IDs alike. Every ID's code is fitted (`ALL_IDS`) either way.
    """

    map_ids: tuple[int, ...] = ()
    rules: StripeRules = StripeRules()
    none_prior: float = 0.1  # a panel in view not of the map: another room's, or stripes mixed up
    observations: list[StripeObservation] = field(default_factory=list)
    max_frames: int = 16
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def hypotheses(self) -> int:
        """The map's IDs plus "none", or the 256 IDs without a map."""
        return len(set(self.map_ids)) + 1 if self.map_ids else len(ALL_IDS)

    max_span_s: float = 2.0  # older frames are dropped: the clock-error search grows with the span

    def add(self, observation: StripeObservation) -> None:
        self.observations.append(observation)
        del self.observations[: -self.max_frames]
        newest = max(o.timestamp_s for o in self.observations)
        self.observations[:] = [o for o in self.observations if newest - o.timestamp_s <= self.max_span_s]

    def _clock_errors(self) -> np.ndarray:
        """Clock-error grid fine enough that the phase slips < 1/clock_steps chip over the span."""
        times = [o.timestamp_s for o in self.observations]
        span_s = max(times) - min(times)
        chip_s = 1.0 / self.rules.chip_rate_hz
        # a slip of a quarter chip over the span costs little: the phase grid itself is an eighth
        step_ppm = chip_s / self.rules.clock_steps_per_chip / max(span_s, 1e-9) * 1e6
        count = int(np.floor(self.rules.max_clock_error_ppm / step_ppm))
        return np.arange(-count, count + 1) * step_ppm

    def decide(self) -> IdDecision:
        usable = [o for o in self.observations if o.samples >= self.rules.min_samples]
        if not usable:
            return IdDecision(None, 0.0, False, 0, 0.0, "no stripes read yet")
        reference = usable[0].timestamp_s
        errors = self._clock_errors()
        setting = (reference, tuple(np.round(errors, 6)))
        cache = {}
        fits = []
        for obs in usable:
            cached = self._cache.get(id(obs))
            if cached is None or cached[0] is not obs or cached[1] != setting:
                cached = (obs, setting, _FrameFit(obs, reference, ALL_IDS, errors, self.rules))
            cache[id(obs)] = cached
            fits.append(cached[2])
        self._cache = cache  # only the frames still in the window
        total = _total_log_likelihood(fits)
        flat = total.reshape(len(ALL_IDS), -1)
        peak = flat.max()
        evidence = np.log(np.maximum(np.exp(flat - peak).sum(axis=1), 1e-300))  # each ID's, over phase and clock
        chips = float(sum(o.chips_seen for o in usable))
        seen = f"from {len(usable)} frame(s), {chips:.1f} chips seen of a {MESSAGE_CHIPS}-chip message"
        if not np.ptp(flat) > 0:
            # no code at any phase explains stripes as deep as it makes them: the posterior would be the prior
            message = f"no code fits the stripes {seen} (none as deep as the code makes them)"
            return IdDecision(None, 0.0, False, len(usable), chips, message)
        if not self.map_ids:
            posterior = _normalised(evidence)
            best = int(np.argmax(posterior))
            confidence = float(posterior[best])
            confident = confidence >= self.rules.confident_posterior
            message = f"ID {best} at posterior {confidence:.3f} {seen}"
            return IdDecision(best, confidence, confident, len(usable), chips, message)
        ids = np.array(sorted(set(self.map_ids)))
        outside = np.setdiff1d(np.arange(len(ALL_IDS)), ids)
        foreign = int(outside[np.argmax(evidence[outside])])
        log_prior = np.log(np.append(np.full(len(ids), (1 - self.none_prior) / len(ids)), self.none_prior))
        posterior = _normalised(np.append(evidence[ids], evidence[foreign]) + log_prior)
        best = int(np.argmax(posterior))
        confidence = float(posterior[best])
        if best == len(ids):
            message = f"stripes read as ID {foreign}, none of the map's, at posterior {confidence:.3f} {seen}"
            return IdDecision(foreign, confidence, False, len(usable), chips, message, in_map=False)
        confident = confidence >= self.rules.confident_posterior
        message = f"ID {ids[best]} at posterior {confidence:.3f} against the map's others and none {seen}"
        return IdDecision(int(ids[best]), confidence, confident, len(usable), chips, message)
