"""The capture protocol that keeps both the pose and the ID readable (docs/vlc.md).

A pose frame wants a normal exposure (~10 ms, saturated panel, sharp edges); at that
exposure the 8.4 ms message is averaged away. So the phone takes, beside each pose frame,
one or more ID frames: same camera, exposure 1/8000 s (a third of a chip; at most one chip,
1/2500 s), ISO raised so
that the panel stays ~200 DN, with `frame_kind = "id"`, its own `timestamp_ns` (first-row
exposure start) and `rolling_shutter_skew_s`. A burst of ID frames is timed so that each
frame starts 0.382 of a message later in the message's cycle than the one before
(golden-ratio stepping), so any few consecutive frames see well-spread parts of the message.
"""

from __future__ import annotations

import math

from server.ingest import LumaFrame
from server.vlc.codec import CHIP_RATE_HZ, MESSAGE_CHIPS
from shared_schemas import FrameKind

ID_EXPOSURE_S = 1.0 / 8000.0
MAX_ID_EXPOSURE_CHIPS = 1.0  # beyond one chip the box average smears neighbouring chips together
GOLDEN_STEP = (3.0 - math.sqrt(5.0)) / 2.0  # 0.382: the most evenly spreading phase step


def message_period_s(chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    return MESSAGE_CHIPS / chip_rate_hz


def stepped_interval_s(nominal_s: float, step: float = GOLDEN_STEP, chip_rate_hz: float = CHIP_RATE_HZ) -> float:
    """The frame interval nearest `nominal_s` that advances the message phase by `step` of a period.

    0.382 (golden ratio) spreads any number of frames evenly; 1/n tiles the message exactly
    with a burst of n frames that each see at least 1/n of it.
    """
    if not nominal_s > 0:
        raise ValueError(f"nominal_s must be positive, got {nominal_s}")
    if not 0 < step < 1:
        raise ValueError(f"step must be a fraction of a period in (0, 1), got {step}")
    period = message_period_s(chip_rate_hz)
    return (max(0, round(nominal_s / period - step)) + step) * period


def id_frame_problem(frame: LumaFrame, chip_rate_hz: float = CHIP_RATE_HZ,
                     max_exposure_chips: float = MAX_ID_EXPOSURE_CHIPS) -> str | None:
    """None when `frame` can carry stripes, else the sentence saying why it cannot."""
    meta = frame.meta
    if meta.rolling_shutter_skew_s is None or meta.rolling_shutter_skew_s <= 0:
        return "rolling_shutter_skew_s is missing: the row times are unknown"
    if meta.exposure_s is None:
        return "exposure_s is missing"
    if meta.exposure_s > max_exposure_chips / chip_rate_hz:
        return (f"exposure_s {meta.exposure_s:.2g} s is longer than {max_exposure_chips / chip_rate_hz:.2g} s: "
                "the code is averaged away")
    if meta.timestamp_ns is None:
        return "timestamp_ns is missing: frames cannot be combined"
    return None


def is_id_frame(frame: LumaFrame) -> bool:
    return getattr(frame.meta, "frame_kind", FrameKind.pose) is FrameKind.id
