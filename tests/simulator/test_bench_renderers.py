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
