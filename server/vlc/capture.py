"""The capture protocol that keeps both the pose and the ID readable (docs/vlc.md, "Capture protocol").

A pose frame wants a normal exposure (saturated panel, sharp edges); at that exposure the
8.4 ms message is averaged away. So each capture of the phone (the Android app's
`IdCapturePlan`) is:

1. one pose frame, `frame_kind = "pose"`, exposed a whole number of message periods
   (`message_period_s`: 8.4 ms or 16.8 ms, where the code averages exactly away);
2. right after it a burst of `ID_BURST_FRAMES` (4) ID frames: same camera, `frame_kind = "id"`,
   exposure `ID_EXPOSURE_S` = 1/8000 s (0.31 chip; frames longer than
   `StripeRules.max_exposure_chips`, one chip = 1/2500 s, are refused by `id_frame_problem`),
   ISO raised so that the panel stays around 200 DN, each with its own `timestamp_ns`
   (first-row exposure start) and `rolling_shutter_skew_s`, both required;
3. timing (`stepped_interval_s`): within a burst each ID frame starts `ID_BURST_STEP` (a
   quarter) of a message later in the message than the one before, so the burst tiles the
   message when each frame sees a quarter of it (`id_frame_interval_s`: 35.70 ms at 30 fps);
   successive captures are `GOLDEN_STEP` (0.382) of a message apart (golden ratio, 498.81 ms
   for a nominal 0.5 s) so that their bursts fill each other's gaps.

The decoder works with any timing (it uses the timestamps); this one makes the fewest frames
cover the whole message. `bench vlc` steps all its frames by the golden step, the more
general case.
"""

from __future__ import annotations

import math

from server.ingest import LumaFrame
from server.vision.beacons import CandidateRules, Candidates, find_beacon_blobs
from server.vision.roi import FrameView
from server.vlc.codec import CHIP_RATE_HZ, MESSAGE_CHIPS, longest_low_run_chips
from server.vlc.decoder import StripeRules, row_time_s
from shared_schemas import FrameKind

# the paper's pose exposure (Section III-B) and the app's: 1.19 messages, a +-4 % ripple (8.4 ms would leave none)
POSE_EXPOSURE_S = 0.01
ID_EXPOSURE_S = 1.0 / 8000.0
# ID-frame brightness (exposure x ISO) as a fraction of the pose frame's: a pose frame's panel clips
# about 4x over, so this keeps the striped panel around 200 DN
ID_BRIGHTNESS_FRACTION = 0.2
ID_BURST_FRAMES = 4  # ID frames after each pose frame (the app's IdCapturePlan.BURST_FRAMES)
ID_BURST_STEP = 1.0 / ID_BURST_FRAMES  # message phase from one ID frame of a burst to the next
GOLDEN_STEP = (3.0 - math.sqrt(5.0)) / 2.0  # 0.382: from one capture to the next, the most evenly spreading step


def message_period_s(chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    return MESSAGE_CHIPS / chip_rate_hz


def stepped_interval_s(nominal_s: float, step: float = GOLDEN_STEP, chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    """The frame interval nearest `nominal_s` that advances the message phase by `step` of a period.

    The default, 0.382 (golden ratio), is the step between captures: it spreads any number
    of frames evenly. 1/n tiles the message exactly with a burst of n frames that each see
    at least 1/n of it (`id_frame_interval_s`).
    """
    if not nominal_s > 0:
        raise ValueError(f"nominal_s must be positive, got {nominal_s}")
    if not 0 < step < 1:
        raise ValueError(f"step must be a fraction of a period in (0, 1), got {step}")
    period = message_period_s(chip_rate_hz)
    return (max(0, round(nominal_s / period - step)) + step) * period


def id_frame_interval_s(nominal_s: float = 1.0 / 30.0, chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    """The interval between the ID frames of a burst: `ID_BURST_STEP` of a message, nearest `nominal_s`."""
    return stepped_interval_s(nominal_s, ID_BURST_STEP, chip_rate_hz)


def longest_id_exposure_s(rules: StripeRules = StripeRules()) -> float:
    """The longest ID exposure the server reads: `rules.max_exposure_chips` at `rules.chip_rate_hz`."""
    return rules.max_exposure_chips / rules.chip_rate_hz


def id_frame_problem(frame: LumaFrame, rules: StripeRules = StripeRules()) -> str | None:
    """None when `frame` can carry stripes, else the sentence saying why it cannot."""
    meta = frame.meta
    if meta.rolling_shutter_skew_s is None or meta.rolling_shutter_skew_s <= 0:
        return "rolling_shutter_skew_s is missing: the row times are unknown"
    if meta.exposure_s is None:
        return "exposure_s is missing"
    longest_s = longest_id_exposure_s(rules)
    if meta.exposure_s > longest_s:
        return f"exposure_s {meta.exposure_s:.2g} s is longer than {longest_s:.2g} s: the code is averaged away"
    if meta.timestamp_ns is None:
        return "timestamp_ns is missing: frames cannot be combined"
    return None


def is_id_frame(frame: LumaFrame) -> bool:
    return getattr(frame.meta, "frame_kind", FrameKind.pose) is FrameKind.id


def longest_dark_run_s(exposure_s: float, chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    """The longest time a panel's rows can stay dark in an ID frame: the code's longest run of 0 chips
    (`longest_low_run_chips`, 2) plus one exposure (a row whose window touches a 1 chip gets its light),
    whatever the LED's modulation depth (a physical bound of the line code, nothing fitted)."""
    return longest_low_run_chips() / chip_rate_hz + exposure_s


def stripe_gap_rows(frame: LumaFrame, rules: StripeRules = StripeRules()) -> int:
    """Rows of `frame` the longest dark run between a panel's stripes spans (0 when `frame` carries no
    stripes): at 1/8000 s and 23.2 us per row (the Mi 8 front camera at a quarter), 40 rows."""
    meta = frame.meta
    if id_frame_problem(frame, rules) is not None:
        return 0
    assert meta.rolling_shutter_skew_s is not None and meta.exposure_s is not None  # id_frame_problem checked
    row_time = row_time_s(meta.rolling_shutter_skew_s, meta.full_size[1])
    return math.ceil(longest_dark_run_s(meta.exposure_s, rules.chip_rate_hz) / row_time)


def frame_blobs(
    frame: LumaFrame, candidates: CandidateRules = CandidateRules(), rules: StripeRules = StripeRules()
) -> Candidates:
    """The beacon candidates of `frame` (`server.vision.beacons.find_beacon_blobs`), bridging the dark rows
    between its stripes (an LED fully off between chips shows a comb of bars; none in a pose frame): the one
    place that works the stripe gap out from the frame (`FrameView.stripe_gap_rows`), so every caller's
    blobs, and their masks (`blob_mask`), are bridged alike."""
    return find_beacon_blobs(frame.pixels, candidates, FrameView.of(frame.meta, stripe_gap_rows(frame, rules)))
