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
    if exposure_s is None or not exposure_s > 0:
        raise ValueError(f"exposure_s must be positive to read stripes, got {exposure_s}")
    y0, x0 = origin_yx
    mask = np.ascontiguousarray(mask, dtype=bool)  # viewed as uint8 for OpenCV
    h, w = mask.shape
    if rules.edge_margin_px > 0:
        size = 2 * rules.edge_margin_px + 1
        mask = cv2.erode(mask.view(np.uint8), np.ones((size, size), np.uint8)).view(bool)
    counts = mask.sum(axis=1)
    rows = np.flatnonzero(counts >= rules.min_pixels_per_row)
    if len(rows) == 0:
        return None
    first, last = rows[0], rows[-1]
    rows = np.arange(first, last + 1)  # the panel is convex: one run of rows
    counts = np.maximum(counts[rows], 1)
    # the pixels inside (0 outside) as float32, summed per row as before: float32 sums, in numpy's order
    inside = pixels[y0 + first : y0 + last + 1, x0 : x0 + w].astype(np.float32)
    inside[~mask[first : last + 1]] = 0.0
    sums = inside.sum(axis=1)
    squares = np.square(inside, out=inside).sum(axis=1)
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


def _frame_log_likelihood(
    obs: StripeObservation,
    reference_s: float,
    candidates: tuple[int, ...],
    clock_errors_ppm: np.ndarray,
    rules: StripeRules,
) -> np.ndarray:
    """(C, phases, clock errors) log-likelihood of one frame; relative to its best fit."""
    lut = _lookup(candidates, round(obs.exposure_s, 9), rules.lut_steps_per_chip, rules.chip_rate_hz)
    steps, count = lut.shape
    chip_s = 1.0 / rules.chip_rate_hz
    period_s = MESSAGE_CHIPS * chip_s
    phases_s = np.arange(MESSAGE_CHIPS * rules.phase_steps_per_chip) * chip_s / rules.phase_steps_per_chip
    # trend basis, whitened by each bin's noise; its orthonormal complement removes gain-free parts
    weights = 1.0 / obs.sigma_dn
    basis = np.vander(obs.position, rules.trend_degree + 1) * weights[:, None]
    q, _ = np.linalg.qr(basis)
    y = obs.values_dn * weights
    y_p = y - q @ (q.T @ y)
    level = float(np.mean(obs.values_dn))
    bins, rows = obs.row_offsets_s.shape
    phases = len(phases_s)
    # blocks of one size, a divisor of the phases; in each, every hypothesis's template is a row fitted by the
    # same calls as when all were fitted at once: the same numbers to the last bit (codes that fit alike tie
    # exactly, and the first in ID order is named)
    block = max(d for d in range(1, phases + 1) if phases % d == 0 and (d == 1 or d * bins <= BLOCK_PHASE_BINS))
    raw = np.empty((block, bins, count), np.float32)  # gathered as whole rows of the table
    row = np.empty_like(raw)
    codes = np.empty((block, count, bins), np.float32)  # (phases, C, n): each bin's share of a 1 chip
    templates = np.empty((block, count, bins))
    trend = np.empty_like(templates)
    explained = np.empty((count, phases, len(clock_errors_ppm)))  # C order as before: decide() sums along phases
    for e, ppm in enumerate(clock_errors_ppm):
        rate = 1.0 + ppm * 1e-6
        times = (obs.timestamp_s - reference_s + obs.row_offsets_s) * rate  # (n, m)
        index = ((phases_s[:, None, None] + times[None]) % period_s / period_s * steps).astype(np.int64) % steps
        for start in range(0, phases, block):
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
            bright = level + gain * (1.0 - codes.mean(axis=-1))
            plausible = (gain >= rules.min_depth * bright) & (norm > 1e-12)
            explained[:, start : start + block, e] = np.where(plausible, along**2 / np.maximum(norm, 1e-12), 0.0).T
    result = float(y_p @ y_p) - explained
    dof = max(1, obs.samples - rules.trend_degree - 2)
    scale = max(1.0, float(result.min()) / dof)  # residuals beyond the pixel noise: the model's own error
    return -0.5 * result / scale


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
        total = np.zeros(())  # broadcasts to the first frame's shape
        setting = (reference, tuple(np.round(errors, 6)))
        cache = {}
        for obs in usable:
            cached = self._cache.get(id(obs))
            if cached is None or cached[0] is not obs or cached[1] != setting:
                cached = (obs, setting, _frame_log_likelihood(obs, reference, ALL_IDS, errors, self.rules))
            cache[id(obs)] = cached
            total = total + cached[2]
        self._cache = cache  # only the frames still in the window
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
