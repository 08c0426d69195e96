"""A frame whose phone applied its own tone curve (`tone_curve: device`, issue 13 item 3): the fix
says so and its uncertainty grows; a map asking more than that is refused, not answered.

Frames: the robustness bench's at quarter resolution through a phone's chain whose ISP applies
the sRGB curve; the same pixels with `tone_curve` absent are what the server saw before.
"""

from dataclasses import replace

import numpy as np

from server.geometry import worst_sigma_2d_m
from server.ingest import LumaFrame
from server.locator import locate
from shared_schemas import FailureReason, ToneCurve
from simulator.benchmarks import AccuracyConfig, accuracy_frame
from simulator.chain import ChainSpec, IspSpec

SRGB = ChainSpec(isp=IspSpec(tone_curve="srgb"))


def _frame(distance_m: float, index: int):
    config = replace(AccuracyConfig(distance_m=distance_m, frames=80, scale=0.25, seed=1), chain=SRGB)
    return accuracy_frame(config, index)


def _unknown_curve(frame: LumaFrame) -> LumaFrame:
    return LumaFrame(frame.pixels, frame.meta.model_copy(update={"tone_curve": None}), frame.camera)


def test_the_chain_reports_its_curve_as_the_app_would():
    assert SRGB.reported_tone_curve() is ToneCurve.device
    assert ChainSpec().reported_tone_curve() is ToneCurve.linear
    frame, _, _ = _frame(1.0, 1)
    assert frame.meta.tone_curve is ToneCurve.device


def test_the_device_curve_is_named_and_widens_the_uncertainty():
    frame, beacon_map, _ = _frame(1.0, 1)
    told = locate(frame, beacon_map)
    untold = locate(_unknown_curve(frame), beacon_map)
    assert told.ok and untold.ok
    assert any("tone curve" in w for w in told.warnings) and not any("tone curve" in w for w in untold.warnings)
    widened = worst_sigma_2d_m(np.asarray(told.position_covariance_m2))
    assert widened > 1.5 * worst_sigma_2d_m(np.asarray(untold.position_covariance_m2))


def test_a_frame_the_curve_leaves_too_uncertain_is_refused():
    # 2 m, quarter resolution: with the curve's term frame 1's corners fix the position to 18 mm
    frame, beacon_map, pose = _frame(2.0, 1)
    result = locate(frame, beacon_map)
    assert not result.ok and result.reason is FailureReason.pose_uncertain, result
    assert any("tone curve" in w for w in result.warnings)
    before = locate(_unknown_curve(frame), beacon_map)  # the curve untold: 7.5 mm off, claiming 4.2 mm
    error = float(np.hypot(*np.subtract(before.position_m, pose.position_m)[:2]))
    assert before.ok and error > 1.5 * worst_sigma_2d_m(np.asarray(before.position_covariance_m2))
