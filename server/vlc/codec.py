"""The beacon's line code: a 5-chip header followed by an 8-bit Biphase Mark Code.

Seed paper, Section IV-D: "a 5-bit header followed by a 8-bit Biphase Mark Code at a
sampling frequency of 2.5 kHz". Here that reads as 2.5 kchip/s (one chip = 0.4 ms):

    message = HEADER (1 1 1 0 0) + BMC(id, 8 bits, most significant bit first) = 21 chips
    period  = 21 chips / 2500 Hz = 8.4 ms, repeated without gaps (119 Hz).

BMC: every bit starts with a level change; a 1 changes level again at mid-bit, a 0 does not.
So inside the data no level lasts longer than 2 chips, while the header holds its level for
3 chips: the header can never occur inside the data, nor across the data/header boundary
(the data always starts with a 1 chip, right after the header's 0 0, and only the header
supplies three equal chips in a row). The decoder therefore finds message starts without
any other framing.

DC balance and flicker: a 1 bit is balanced (one chip high, one low); a 0 bit is two equal
chips, and because every bit starts with a transition the 0 bits alternate between high and
low pairs. Every message has 11 or 12 high chips of 21 (checked for all 256 ids in the
tests), so all panels are equally bright to within 1/21 in a long exposure. The pattern
repeats at 119 Hz, above flicker fusion.

Modulation depth d: a 0 chip is `1 - d` of a 1 chip (`LedWaveform.depth`). The default,
`DEFAULT_DEPTH` = 0.7, keeps the LED at 0.3 between chips; a real driver keyed on and off (OOK,
PWM at full depth) has d = 1.0, and a short exposure then shows separate bars with fully dark
rows between them, never longer than `longest_low_run_chips()` (2: the header's `0 0`, BMC's
at most 2 equal chips).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

CHIP_RATE_HZ = 2500.0
HEADER = (1, 1, 1, 0, 0)
DATA_BITS = 8
MESSAGE_CHIPS = len(HEADER) + 2 * DATA_BITS  # 21
MAX_ID = 2**DATA_BITS - 1
DEFAULT_DEPTH = 0.7  # the LED's low level 0.3 of its high: never off (a depth of 1.0 is fully off)


def _check_id(beacon_id: int) -> None:
    if isinstance(beacon_id, bool) or not isinstance(beacon_id, (int, np.integer)):
        raise TypeError(f"beacon_id must be an integer, got {type(beacon_id).__name__}")
    if not 0 <= beacon_id <= MAX_ID:
        raise ValueError(f"beacon_id must be in 0..{MAX_ID}, got {beacon_id}")


def bmc_chips(bits: list[int], start_level: int) -> list[int]:
    """Biphase Mark chips of `bits`, two per bit, starting after a chip at `start_level`."""
    chips: list[int] = []
    level = start_level
    for bit in bits:
        level ^= 1  # a transition at every bit start
        chips.append(level)
        if bit:
            level ^= 1  # and one at mid-bit for a 1
        chips.append(level)
    return chips


def encode(beacon_id: int) -> np.ndarray:
    """One message (21,) uint8 of chips (1 = LED high) for `beacon_id` in 0..255."""
    _check_id(beacon_id)
    bits = [(beacon_id >> (DATA_BITS - 1 - k)) & 1 for k in range(DATA_BITS)]
    return np.array(list(HEADER) + bmc_chips(bits, HEADER[-1]), dtype=np.uint8)


def _bmc_bits(data: np.ndarray, previous_level: int) -> list[int] | None:
    """Bits of BMC chips, or None when a bit does not start with a transition."""
    bits = []
    level = previous_level
    for first, second in data.reshape(-1, 2):
        if first == level:
            return None
        bits.append(int(first != second))
        level = second
    return bits


def header_starts(chips: np.ndarray) -> list[int]:
    """Indices where the header starts in a cyclic chip sequence."""
    n = len(chips)
    header = np.array(HEADER)
    return [i for i in range(n) if np.array_equal(chips[(i + np.arange(len(header))) % n], header)]


def decode(chips: np.ndarray) -> int | None:
    """The id of one cyclic message of 21 chips at any rotation, or None if it is not one.

    The header must occur exactly once and the data must be valid BMC.
    """
    chips = np.asarray(chips).astype(np.uint8).ravel()
    if len(chips) != MESSAGE_CHIPS or np.any(chips > 1):
        return None
    starts = header_starts(chips)
    if len(starts) != 1:
        return None
    rolled = np.roll(chips, -starts[0])
    bits = _bmc_bits(rolled[len(HEADER) :], HEADER[-1])
    if bits is None:
        return None
    return int(sum(bit << (DATA_BITS - 1 - k) for k, bit in enumerate(bits)))


@cache  # a property of the code: derived from it once (256 encodings), not on every ID frame
def longest_low_run_chips() -> int:
    """The longest run of 0 chips in any message repeated without gaps, over all IDs (cyclic)."""
    longest = 0
    for beacon_id in range(MAX_ID + 1):
        chips = np.tile(encode(beacon_id), 2)  # two periods: runs across the message boundary count
        runs = np.diff(np.flatnonzero(np.diff(np.concatenate([[1], chips, [1]])) != 0))[::2]
        longest = max(longest, int(runs.max(initial=0)))
    return longest


@dataclass(frozen=True)
class LedWaveform:
    """The periodic light of one beacon: `chips` repeated at `chip_rate_hz`.

    Levels are relative radiance: `high_level` for a 1 chip, `low_level` for a 0 chip
    (`depth` = 1 - low / high: 0.7 by default, 1.0 fully off between chips). The message starts
    at t = `phase_s` on the LED's own clock, which runs `clock_error_ppm` fast against the
    camera's clock.
    """

    chips: tuple[int, ...]
    chip_rate_hz: float = CHIP_RATE_HZ
    low_level: float = round(1.0 - DEFAULT_DEPTH, 12)  # 0.3 (rounded as in `for_beacon`)
    high_level: float = 1.0
    phase_s: float = 0.0
    clock_error_ppm: float = 0.0

    def __post_init__(self) -> None:
        if self.chip_rate_hz <= 0:
            raise ValueError(f"chip_rate_hz must be positive, got {self.chip_rate_hz}")
        if not 0 <= self.low_level <= self.high_level:
            raise ValueError(f"need 0 <= low_level <= high_level, got {self.low_level}, {self.high_level}")
        if len(self.chips) == 0 or any(c not in (0, 1) for c in self.chips):
            raise ValueError("chips must be a non-empty sequence of 0 and 1")

    @classmethod
    def for_beacon(cls, beacon_id: int, depth: float | None = None, **kwargs) -> LedWaveform:
        """The waveform of `beacon_id`'s code; `depth` (0-1) sets `low_level` to (1 - depth) x `high_level`
        (so not both: a ValueError)."""
        if depth is not None:
            if "low_level" in kwargs:
                raise ValueError(f"give depth or low_level, not both (got {depth}, {kwargs['low_level']})")
            if not 0.0 <= depth <= 1.0:
                raise ValueError(f"depth must be in 0..1, got {depth}")
            # rounded: depth 0.7 is the low level 0.3 itself, not 0.30000000000000004 (figures stay bit-identical)
            kwargs["low_level"] = round((1.0 - depth) * kwargs.get("high_level", 1.0), 12)
        return cls(chips=tuple(int(c) for c in encode(beacon_id)), **kwargs)

    @property
    def depth(self) -> float:
        """Modulation depth: 1 - low / high (0.7 by default, 1.0 when the LED is off between chips)."""
        return 1.0 - self.low_level / self.high_level if self.high_level > 0 else 0.0

    @property
    def chip_s(self) -> float:
        return 1.0 / self.chip_rate_hz

    @property
    def period_s(self) -> float:
        return len(self.chips) / self.chip_rate_hz

    @property
    def levels(self) -> np.ndarray:
        return np.where(np.array(self.chips) > 0, self.high_level, self.low_level)

    @property
    def mean_level(self) -> float:
        return float(self.levels.mean())

    def _integral(self, t_s: np.ndarray) -> np.ndarray:
        """Integral of the radiance from the message start to LED-clock time `t_s` (s)."""
        levels = self.levels
        chip_s = self.chip_s
        per_period = levels.sum() * chip_s
        prefix = np.concatenate([[0.0], np.cumsum(levels)]) * chip_s
        periods = np.floor(t_s / self.period_s)
        within = t_s - periods * self.period_s
        index = np.minimum((within / chip_s).astype(np.int64), len(levels) - 1)
        return periods * per_period + prefix[index] + levels[index] * (within - index * chip_s)

    def window_means(self, start_s: np.ndarray, exposure_s: float) -> np.ndarray:
        """Mean radiance over [start, start + exposure_s] for each camera-clock `start_s`."""
        if exposure_s <= 0:
            raise ValueError(f"exposure_s must be positive, got {exposure_s}")
        rate = 1.0 + self.clock_error_ppm * 1e-6
        start = (np.asarray(start_s, dtype=float) - self.phase_s) * rate
        return (self._integral(start + exposure_s * rate) - self._integral(start)) / (exposure_s * rate)
