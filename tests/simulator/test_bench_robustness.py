"""`lumipose bench robustness`: the accuracy bench's frames through the phone chain, one effect at a time."""

import numpy as np

from simulator.bench_robustness import RobustnessConfig, effects, format_robustness, run_robustness
from simulator.benchmarks import AccuracyConfig, accuracy_frame
from simulator.chain import ChainSpec


def test_every_chain_sees_the_same_pose_and_an_effect_changes_the_frame():
    base = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1)
    plain, _, pose = accuracy_frame(base, 0)
    off, _, off_pose = accuracy_frame(AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, chain=ChainSpec()), 0)
    curve = effects(1.0)["tone S-curve"][1]
    s_shaped, _, s_pose = accuracy_frame(AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, chain=curve), 0)
    np.testing.assert_array_equal(pose.position_m, off_pose.position_m)  # the same draws with or without a chain
    np.testing.assert_array_equal(off_pose.rotation_wc, s_pose.rotation_wc)
    assert off.meta.gravity_camera == s_shaped.meta.gravity_camera  # the chain's noise has its own generator
    assert off.pixels.shape == s_shaped.pixels.shape == plain.pixels.shape
    # sRGB then the S lifts the dark ceiling (the docs: as the curve says); the panel stays clipped
    assert np.median(s_shaped.pixels) > np.median(off.pixels) + 10
    assert s_shaped.pixels.max() == off.pixels.max() == 255


def test_the_bench_reports_every_field_and_an_effect_differs_from_the_baseline():
    config = RobustnessConfig(distances_m=(1.0,), scales=(0.1,), frames=2, effects=("tone",))
    report = run_robustness(config, workers=1)
    names = [c["effect"] for c in report["cells"]]
    assert names == ["no chain", "ISP off", "tone sRGB (preset)", "tone S-curve", "ISP on"]
    for cell in report["cells"]:
        assert {"coverage_pct", "wrong_fixes", "refusals", "scale", "distance_m", "frames"} <= set(cell)
        if cell["coverage_pct"] > 0:
            assert {"mean_mm", "p95_mm", "max_mm"} <= set(cell)
    cells = {c["effect"]: c for c in report["cells"]}
    assert cells["ISP off"]["mean_over_isp_off"] == 1.0
    assert cells["tone S-curve"].get("mean_mm") != cells["ISP off"].get("mean_mm")
    # no quarter resolution
    assert [t["met"] is None for t in report["targets"]] == [True, True, True, False, False, False]
    text = format_robustness(report)
    assert "tone S-curve" in text and "targets" in text


def test_the_phone_group_puts_the_stages_an_outside_check_used_together():
    """Issue 29 item 4: defocus, hand motion, sharpening and JPEG in one cell (each alone was a cell of its own),
    so that the bench sees what a phone does to an edge when they meet."""
    config = RobustnessConfig(distances_m=(1.0,), scales=(0.1,), frames=2, effects=("phone",))
    cells = {c["effect"]: c for c in run_robustness(config, workers=1)["cells"]}
    assert set(cells) == {"no chain", "ISP off", "ISP on", "phone still", "phone tremor"}
    chain = cells["phone tremor"]["chain"]
    assert chain["optics"]["focus_distance_m"] == 0.75 and chain["isp"]["sharpen_amount"] == 0.8
    assert chain["jpeg_quality"] == 90 and not ChainSpec.model_validate(chain).motion.still
    assert cells["phone still"]["coverage_pct"] == 100.0
