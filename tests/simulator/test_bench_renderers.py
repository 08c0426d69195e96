"""`lumipose bench accuracy --renderer`: the same frames from both renderers (Blender needs bpy)."""

import numpy as np
import pytest

from simulator.benchmarks import AccuracyConfig, accuracy_frame, renderer_ratios


def test_blender_draws_the_same_frame_as_ours_through_the_same_sensor():
    pytest.importorskip("bpy", reason="bpy (Blender as a module) is an optional extra: pip install -e '.[blender]'")
    ours_config = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1)
    ours, _, pose = accuracy_frame(ours_config, 0)
    blender, _, blender_pose = accuracy_frame(AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, renderer="blender"), 0)
    np.testing.assert_array_equal(pose.position_m, blender_pose.position_m)  # the same geometry
    bright_ours, bright_blender = ours.pixels > 128, blender.pixels > 128
    overlap = (bright_ours & bright_blender).sum() / (bright_ours | bright_blender).sum()
    assert overlap > 0.95, overlap  # the same panel in the same place, edges within a pixel
    assert abs(int(np.median(ours.pixels)) - int(np.median(blender.pixels))) <= 1  # the same background


def test_an_unknown_renderer_is_refused():
    with pytest.raises(ValueError, match="renderer"):
        accuracy_frame(AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, renderer="povray"), 0)


def test_ratios_pair_the_renderers_by_distance():
    reports = [{"distance_m": d, "renderer": r, "modes": {"auto": {"mean_mm": m}}}
               for d, r, m in [(1.0, "ours", 0.5), (1.0, "blender", 1.0), (2.0, "ours", 2.0)]]
    assert renderer_ratios(reports) == [{"distance_m": 1.0, "mode": "auto", "ours_mean_mm": 0.5,
                                         "blender_mean_mm": 1.0, "ratio": 2.0}]


def test_blender_frames_go_through_a_phone_chain():
    """Issue 29 item 4: Cycles' light through the chain an outside check used (defocus, sharpening, JPEG), the same
    pose as ours, located; the sharpening's dark ring is in the frame (below the background beside the panel)."""
    pytest.importorskip("bpy", reason="bpy (Blender as a module) is an optional extra: pip install -e '.[blender]'")
    from dataclasses import replace

    from server.locator import locate
    from simulator import blender
    from simulator.bench_robustness import phone_chain

    config = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, renderer="blender", chain=phone_chain(1.0))
    cheap = replace(blender.FRAME_SETTINGS, samples=64, adaptive_threshold=0.01)  # a 0.1 scale frame in ~1 s
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(blender, "FRAME_SETTINGS", cheap)
        frame, beacon_map, pose = accuracy_frame(config, 0)
    _, _, ours_pose = accuracy_frame(replace(config, renderer="ours"), 0)
    np.testing.assert_array_equal(pose.position_m, ours_pose.position_m)
    assert frame.pixels.min() < np.median(frame.pixels) - 2  # the unsharp mask's undershoot beside the edge
    result = locate(frame, beacon_map)
    assert result.ok, result.message
    assert np.hypot(*np.subtract(result.position_m, pose.position_m)[:2]) < 0.01


def test_blender_refuses_a_moving_or_binned_chain():
    pytest.importorskip("bpy", reason="bpy (Blender as a module) is an optional extra: pip install -e '.[blender]'")
    from simulator.bench_robustness import phone_chain
    from simulator.chain import PixelSpec
    from simulator.motion import MotionSpec

    binned = phone_chain(1.0).model_copy(update={"pixels": PixelSpec(binning=2)})
    for chain, field in [(phone_chain(1.0, MotionSpec.tremor()), "chain.motion"), (binned, "chain.pixels.binning")]:
        config = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, renderer="blender", chain=chain)
        with pytest.raises(ValueError, match=field):
            accuracy_frame(config, 0)
