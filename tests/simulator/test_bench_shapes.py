"""`lumipose bench accuracy --shape` plumbing on small frames (the figures are CLI runs, docs/accuracy.md)."""

import json
import math

import numpy as np
import pytest

from lumipose_cli.main import main
from server.camera import intrinsics_from_profile
from shared_schemas import FailureReason, PanelShape, device_profiles
from simulator.bench_shapes import (
    PROFILE_ID,
    SHAPES,
    ShapesConfig,
    draw_shape_pose,
    format_shapes,
    shape_cases,
    summarize_shape,
)
from simulator.render import beacon_outline_px


def test_the_issues_panels_hang_1_4_m_above_the_camera():
    cases = shape_cases()
    assert list(cases) == list(SHAPES)
    assert cases["square-174"].beacon.extent_m == (0.174, 0.174)
    assert cases["square-600"].beacon.extent_m == (0.6, 0.6)
    assert cases["rectangle-1200x300"].beacon.extent_m == (1.2, 0.3)
    assert cases["rectangle-1200x300"].max_yaw_deg == 80.0  # its rule holds within 90 degrees
    for key in ("circle-200", "circle-200-uncapped"):
        assert cases[key].beacon.shape is PanelShape.circle and cases[key].heading
    assert cases["circle-200-uncapped"].outline_fit.max_sigma_m > cases["circle-200"].outline_fit.max_sigma_m
    assert all(case.beacon.center_m[2] == pytest.approx(2.7 - 1.3) for case in cases.values())


@pytest.mark.parametrize(
    "key, scale",
    # at full resolution the 1.2 m panel spans ~3350 of the frame's 3880 px across
    [("square-600", 0.2), ("rectangle-1200x300", 0.2), ("rectangle-1200x300", 1.0), ("circle-200", 0.2)],
)
def test_drawn_poses_hold_the_whole_panel(key, scale):
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * scale), round(profile.height * scale)
    camera = intrinsics_from_profile(profile, width, height)
    config, case = ShapesConfig(scale=scale), shape_cases()[key]
    rng = np.random.default_rng(3)
    yaws = []
    for _ in range(8):
        pose, _ = draw_shape_pose(config, case, camera, width, height, rng)
        outline = beacon_outline_px(case.beacon, camera, pose)
        assert (outline.min(axis=0) > config.margin_px).all()
        assert (outline.max(axis=0) < [width - config.margin_px, height - config.margin_px]).all()
        assert math.degrees(math.acos(pose.rotation_wc[2, 2])) <= config.max_tilt_deg + 1e-9
        yaws.append(math.degrees(math.atan2(pose.rotation_wc[1, 0], pose.rotation_wc[0, 0])))
        assert pose.position_m[2] == 0.0
    assert max(abs(y) for y in yaws) <= case.max_yaw_deg
    if key == "rectangle-1200x300":
        assert max(abs(y) for y in yaws) > 45.0  # beyond the square's rule


def _sample(ok=True, error_mm=1.0, delta_mm=(1.0, 0.0), covariance_mm2=None, reason=None, yaw_error=0.0):
    pose = {"position_m": [0.1, 0.2, 0.0], "yaw_deg": 5.0, "relative_yaw_deg": 5.0, "tilt_deg": 2.0}
    sample = {"shape": "x", "index": 0, **pose, "heading_error_deg": None, "attitude_redraws": 1, "locate_ms": 10.0,
              "ok": ok}  # fmt: skip
    if not ok:
        return sample | {"reason": reason, "message": "why"}
    sample |= {"error_2d_m": error_mm / 1000, "error_3d_m": 2 * error_mm / 1000, "yaw_error_deg": yaw_error,
               "orientation_rule": "yaw_within_90deg"}  # fmt: skip
    if covariance_mm2 is not None:
        covariance = np.array(covariance_mm2) / 1e6
        delta = np.array(delta_mm) / 1000
        sample |= {"mahalanobis2": float(delta @ np.linalg.solve(covariance, delta)),
                   "sigma_2d_m": math.sqrt(np.linalg.eigvalsh(covariance).max()),
                   "sigma_rms_2d_m": math.sqrt(np.trace(covariance))}  # fmt: skip
    return sample


def test_summary_counts_the_ellipse_refusals_and_turned_fixes():
    diagonal = [[1.0, 0.0], [0.0, 4.0]]  # sigma 1 mm along X, 2 mm along Y
    samples = [
        _sample(error_mm=2.0, delta_mm=(2.0, 0.0), covariance_mm2=diagonal),  # d^T C^-1 d = 4: inside
        _sample(error_mm=3.0, delta_mm=(3.0, 0.0), covariance_mm2=diagonal),  # 9: outside
        _sample(error_mm=400.0, yaw_error=-180.0),  # turned by the rule, no covariance
        _sample(ok=False, reason="beacon_cut_off"),
        _sample(ok=False, reason="beacon_cut_off"),
        _sample(ok=False, reason="pose_ambiguous"),
    ]
    row = summarize_shape(samples)
    assert row["frames"] == 6 and row["coverage_pct"] == pytest.approx(50.0)
    assert row["mean_mm"] == pytest.approx(135.0) and row["max_mm"] == pytest.approx(400.0)
    assert row["mean_3d_mm"] == pytest.approx(270.0)
    assert row["with_covariance"] == 2 and row["inside_95_pct"] == 50.0
    assert row["mean_sigma_2d_mm"] == pytest.approx(2.0)
    assert row["refusals"] == {"beacon_cut_off": 2, "pose_ambiguous": 1}
    assert row["turned_fixes"] == 1 and row["orientation_rules"] == {"yaw_within_90deg": 3}
    assert row["median_locate_ms"] == 10.0 and row["attitude_redraws"] == 6


def test_cli_accuracy_shape_prints_a_row_per_shape(capsys):
    argv = ["bench", "accuracy", "--shape", "--frames", "2", "--scale", "0.2", "--workers", "2", "--seed", "4"]
    assert main([*argv, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["frame"] == "776x1037" and report["config"]["frames"] == 2
    assert list(report["shapes"]) == list(SHAPES)
    for key, row in report["shapes"].items():
        assert row["frames"] == 2
        refused = sum(row["refusals"].values())
        assert len(row["refused_frames"]) == refused
        assert row["coverage_pct"] == pytest.approx(100.0 * (2 - refused) / 2)
        assert all(r in {reason.value for reason in FailureReason} for r in row["refusals"])
        if refused < 2:
            assert {"mean_mm", "std_mm", "max_mm", "p95_mm", "mean_3d_mm"} <= set(row)
    capped, uncapped = (report["shapes"][key] for key in ("circle-200", "circle-200-uncapped"))
    frames = [[f for f in report["frames"] if f["shape"] == key] for key in ("circle-200", "circle-200-uncapped")]
    assert [f["position_m"] for f in frames[0]] == [f["position_m"] for f in frames[1]]  # the same frames
    assert all(f["heading_error_deg"] is not None for f in frames[0])
    assert uncapped["coverage_pct"] >= capped["coverage_pct"]
    text = format_shapes(report)
    assert text.splitlines()[2].split()[:4] == ["shape", "cover", "mean", "std"]
    assert "1200 x 300 mm" in text and "circle" in text
    assert main([*argv[:3], "--frames", "0"]) == 2
