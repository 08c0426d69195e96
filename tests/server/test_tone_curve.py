"""A frame's tone curve (issue 13 item 3). The sRGB preset (`tone_curve: srgb`) is undone before
any stage reads the pixels, so the frame is located as a linear one; a device's own curve
(`device`) cannot be: the fix says so and its uncertainty grows, and a map asking more than that
is refused, not answered.

Frames: the robustness bench's at quarter resolution through a phone's chain whose ISP applies
the sRGB curve (reported `srgb`, as the app does for the preset; `device` stands for a device whose
own curve happens to be sRGB); the same pixels with `tone_curve` absent are what the server saw before.
"""

from dataclasses import replace

import numpy as np
import pytest

from lumipose_client.crop import crop_frame
from server.geometry import worst_sigma_2d_m
from server.ingest import LumaFrame, decode_frame
from server.locator import locate
from server.tone import SRGB_TO_LINEAR_DN, linearized
from server.tracking.devices import Devices
from shared_schemas import Crop, FailureReason, ToneCurve
from shared_schemas.windows import frame_levels
from simulator.benchmarks import AccuracyConfig, accuracy_frame
from simulator.chain import ChainSpec, IspSpec, srgb
from tests.helpers import TWO_PANELS, two_panel_frame
from tests.server.test_rooms import big_panels, room_id_frame

SRGB = ChainSpec(isp=IspSpec(tone_curve="srgb"))


def _frame(distance_m: float, index: int, chain: ChainSpec = SRGB):
    config = replace(AccuracyConfig(distance_m=distance_m, frames=80, scale=0.25, seed=1), chain=chain)
    return accuracy_frame(config, index)


def _told(frame: LumaFrame, curve: ToneCurve | None) -> LumaFrame:
    return LumaFrame(frame.pixels, frame.meta.model_copy(update={"tone_curve": curve}), frame.camera)


def _unknown_curve(frame: LumaFrame) -> LumaFrame:
    return _told(frame, None)


def _device_frame(distance_m: float, index: int):
    frame, beacon_map, pose = _frame(distance_m, index)
    return _told(frame, ToneCurve.device), beacon_map, pose


def _error_mm(result, pose) -> float:
    assert result.ok, result
    return 1000.0 * float(np.hypot(*np.subtract(result.position_m, pose.position_m)[:2]))


def test_the_chain_reports_its_curve_as_the_app_would():
    assert SRGB.reported_tone_curve() is ToneCurve.srgb
    assert ChainSpec(isp=IspSpec(tone_curve="s_curve")).reported_tone_curve() is ToneCurve.device
    assert ChainSpec().reported_tone_curve() is ToneCurve.linear
    frame, _, _ = _frame(1.0, 1)
    assert frame.meta.tone_curve is ToneCurve.srgb


def test_the_table_is_the_inverse_of_the_simulators_srgb_curve():
    assert SRGB_TO_LINEAR_DN[0] == 0 and SRGB_TO_LINEAR_DN[255] == 255
    grid = np.linspace(0.0, 1.0, 100_001)
    inverse = 255.0 * np.interp(np.arange(256) / 255.0, srgb(grid), grid)  # the chain's curve, inverted numerically
    assert np.abs(SRGB_TO_LINEAR_DN - inverse).max() <= 0.5 + 1e-3
    assert SRGB_TO_LINEAR_DN[188] == 128  # sRGB's encoding of half the light: 0.7354


def test_linearized_maps_the_pixels_and_the_window_levels_and_says_linear():
    frame, _, _ = _frame(1.0, 1)
    crop = Crop(x=0, y=0, full_width=frame.meta.width, full_height=frame.meta.height, levels_dn=[20.0, 187.5])
    windowed = LumaFrame(frame.pixels, frame.meta.model_copy(update={"crop": crop}), frame.camera)
    linear = linearized(windowed)
    whole = SRGB_TO_LINEAR_DN[frame.pixels]
    lit = whole > 40  # the panel and its edges: mapped; what is not mapped is left zero
    np.testing.assert_array_equal(linear.pixels[lit], whole[lit])
    assert np.all(linear.pixels[linear.pixels != whole] == 0)
    assert not linear.pixels.flags.writeable
    assert linear.meta.tone_curve is ToneCurve.linear
    assert linear.meta.crop is not None and linear.meta.crop.levels_dn is not None
    background, plateau = linear.meta.crop.levels_dn
    assert background == SRGB_TO_LINEAR_DN[20]
    assert plateau == pytest.approx((int(SRGB_TO_LINEAR_DN[187]) + int(SRGB_TO_LINEAR_DN[188])) / 2)
    assert linearized(linear) is linear  # once only
    for curve in (ToneCurve.linear, ToneCurve.device, None):
        other = _told(frame, curve)
        assert linearized(other) is other


def test_an_srgb_frame_is_located_as_well_as_a_linear_one():
    # The clipped-edge model measures light: on the encoded pixels (the curve untold, what the
    # server did before `srgb`) the mean at 2 m is several times the linear chain's.
    for distance_m in (1.0, 2.0):
        linear, srgb_told, untold = [], [], []
        for index in range(1, 5):
            frame, beacon_map, pose = _frame(distance_m, index, ChainSpec())
            linear.append(_error_mm(locate(frame, beacon_map), pose))
            frame, beacon_map, pose = _frame(distance_m, index)
            told = locate(frame, beacon_map)
            assert not any("tone curve" in w for w in told.warnings)
            srgb_told.append(_error_mm(told, pose))
            untold.append(_error_mm(locate(_unknown_curve(frame), beacon_map), pose))
        assert np.mean(srgb_told) <= 2.0 * max(np.mean(linear), 0.5), (distance_m, srgb_told, linear)
        if distance_m == 2.0:
            assert np.mean(untold) > 2.0 * np.mean(linear), (untold, linear)


def test_a_window_of_an_srgb_frame_gives_the_whole_frames_fix():
    # the client measures the window's levels on the encoded frame; the server maps them as the pixels
    frame, beacon_map, pose = _frame(2.0, 2)
    meta, data = crop_frame(np.asarray(frame.pixels), frame.meta)
    assert meta.crop is not None and meta.crop.levels_dn is not None and meta.tone_curve is ToneCurve.srgb
    window = decode_frame(data, meta)
    crop = linearized(window).meta.crop
    assert crop is not None and crop.levels_dn == list(frame_levels(SRGB_TO_LINEAR_DN[frame.pixels]))  # 50 -> 8
    whole, cut = locate(frame, beacon_map), locate(window, beacon_map)
    assert whole.ok and cut.ok and cut.warnings == whole.warnings
    # as a linear frame's window: 1-3 um apart (the same arithmetic in the window's coordinates)
    np.testing.assert_allclose(cut.position_m, whole.position_m, atol=1e-5)
    assert _error_mm(whole, pose) < 5.0


def test_the_device_curve_is_named_and_widens_the_uncertainty():
    frame, beacon_map, _ = _device_frame(1.0, 1)
    told = locate(frame, beacon_map)
    untold = locate(_unknown_curve(frame), beacon_map)
    assert told.ok and untold.ok
    assert any("tone curve" in w for w in told.warnings) and not any("tone curve" in w for w in untold.warnings)
    widened = worst_sigma_2d_m(np.asarray(told.position_covariance_m2))
    assert widened > 1.5 * worst_sigma_2d_m(np.asarray(untold.position_covariance_m2))


def test_a_frame_the_curve_leaves_too_uncertain_is_refused():
    # 2 m, quarter resolution: with the curve's term frame 1's corners fix the position to 18 mm
    frame, beacon_map, pose = _device_frame(2.0, 1)
    result = locate(frame, beacon_map)
    assert not result.ok and result.reason is FailureReason.pose_uncertain, result
    assert any("tone curve" in w for w in result.warnings)
    untold = locate(_unknown_curve(frame), beacon_map)  # the same pixels, the curve untold: a fix
    assert untold.ok and not any("tone curve" in w for w in untold.warnings)


def _encoded(frame: LumaFrame) -> LumaFrame:
    """A linear render as the sRGB preset encodes it, reported `srgb`."""
    pixels = np.rint(255.0 * srgb(frame.pixels / 255.0)).astype(np.uint8)
    return LumaFrame(pixels, frame.meta.model_copy(update={"tone_curve": ToneCurve.srgb}), frame.camera)


def test_the_room_and_device_paths_read_an_srgb_frame_as_light():
    # a room's ID frame whose panels are named by their own stripes (server.rooms, server.vlc) ...
    beacon_map = big_panels((0.7, 0.0))
    room_frame = _encoded(room_id_frame(beacon_map))
    room = locate(room_frame, beacon_map)
    assert room.ok and room.vlc is not None and room.vlc.confident, room
    # ... and a device's session, which keeps a burst's ID frames for its pose frame (server.tracking)
    burst = [two_panel_frame(level_dn=200.0, exposure_s=1 / 8000, seed=k, t_s=0.0189 * k) for k in range(4)]
    frames = [_encoded(frame) for frame in (*burst, two_panel_frame(t_s=0.1))]
    devices = Devices()
    answer = [locate(frame, TWO_PANELS, device_id="phone", devices=devices) for frame in frames][-1]
    assert answer.ok and answer.vlc is not None and answer.vlc.confident, answer
