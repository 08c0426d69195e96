"""`lumipose bench partial` plumbing on small frames (the figures are CLI runs, docs/accuracy.md)."""

import json

import numpy as np
import pytest

from lumipose_cli.main import main
from server.camera import intrinsics_from_profile
from shared_schemas import FailureReason, device_profiles
from simulator.bench_partial import (
    BINS,
    NO_REASON,
    PROFILE_ID,
    SHARE_RANGE,
    PartialConfig,
    bench_beacon,
    clip_to_frame,
    draw_partial_pose,
    format_partial,
    frame_size,
    issue_summary,
    mahalanobis2,
    run_partial,
    stratified_share,
    summarize_frames,
    visible_share,
)
from simulator.render import beacon_outline_px, coverage_map, exact_polygon_area_px


def test_clip_to_frame_keeps_the_part_inside():
    square = np.array([[-5.5, 1.5], [4.5, 1.5], [4.5, 11.5], [-5.5, 11.5]])  # 10 x 10, half left of x = -0.5
    assert exact_polygon_area_px(clip_to_frame(square, 20, 20)) == pytest.approx(50.0)
    assert visible_share(square, 20, 20) == pytest.approx(0.5)
    assert visible_share(square + [6.0, 0.0], 20, 20) == pytest.approx(1.0)
    assert visible_share(square - [20.0, 0.0], 20, 20) == 0.0
    corner = square + [0.0, -7.0]  # also half above y = -0.5
    assert visible_share(corner, 20, 20) == pytest.approx(0.25)


@pytest.mark.parametrize("scale", [0.1, 0.25])
@pytest.mark.parametrize("distance_m", [1.0, 3.0])
def test_drawn_poses_have_the_requested_visible_share(scale, distance_m):
    width, height = frame_size(scale)
    camera = intrinsics_from_profile(device_profiles()[PROFILE_ID], width, height)
    beacon = bench_beacon(distance_m)
    rng = np.random.default_rng(7)
    for share in (SHARE_RANGE[0], 0.45, 0.7, SHARE_RANGE[1]):
        drawn = draw_partial_pose(PartialConfig(), beacon, camera, width, height, share, rng)
        outline = beacon_outline_px(beacon, camera, drawn.pose)
        assert drawn.visible_share == pytest.approx(share, abs=1e-3)
        # the renderer's own pixel coverage agrees: the frame shows that share of the panel
        rendered = coverage_map(outline, width, height).sum() / exact_polygon_area_px(outline)
        assert rendered == pytest.approx(share, abs=3e-3)
        assert drawn.tilt_deg <= 10.0 and abs(drawn.yaw_deg) <= 40.0
        assert drawn.pose.position_m[2] == 0.0


def test_shares_are_stratified_over_the_range():
    rng = np.random.default_rng(1)
    shares = [stratified_share(i, 4, rng) for i in range(4)]
    edges = np.linspace(*SHARE_RANGE, 5)
    assert all(low <= s < high for s, low, high in zip(shares, edges[:-1], edges[1:], strict=True))


def _record(share, error_mm=None, reason=None, covariance_mm2=None, delta_mm=(0.0, 0.0)):
    inside = m2 = None
    if covariance_mm2 is not None:
        m2 = mahalanobis2(np.array(delta_mm) / 1000.0, np.array(covariance_mm2) / 1e6)
        inside = None if m2 is None else m2 <= 5.991
    return {
        "scale": 0.25,
        "distance_m": 1.0,
        "visible_share": share,
        "ok": reason is None,
        "reason": reason,
        "error_2d_mm": error_mm,
        "mahalanobis2": m2,
        "inside_95": inside,
    }


def test_summaries_count_the_ellipse_the_outliers_and_every_refusal():
    diagonal = [[1.0, 0.0], [0.0, 4.0]]  # sigma 1 mm along X, 2 mm along Y
    records = [
        _record(0.5, 2.0, covariance_mm2=diagonal, delta_mm=(2.0, 0.0)),  # d^T C^-1 d = 4: inside
        _record(0.5, 3.0, covariance_mm2=diagonal, delta_mm=(3.0, 0.0)),  # 9: outside
        _record(0.5, 1.0),  # no covariance: n/a
        _record(0.5, 80.0, covariance_mm2=[[1.0, 0.0], [0.0, -1.0]], delta_mm=(80.0, 0.0)),  # not an ellipse
        _record(0.3, reason="beacon_cut_off"),
        _record(0.3, reason="beacon_cut_off"),
        _record(0.9, reason=None) | {"ok": False},  # a refusal without its reason is shown, not hidden
    ]
    summary = summarize_frames(records)
    assert summary["frames"] == 7 and summary["fixed"] == 4
    assert summary["coverage_pct"] == pytest.approx(400 / 7)
    assert summary["mean_mm"] == pytest.approx(21.5) and summary["max_mm"] == 80.0
    assert summary["over_50mm"] == 1
    assert summary["inside_95"] == 1 and summary["inside_95_pct"] == 50.0 and summary["ellipse_na"] == 2
    assert summary["refusals"] == {"beacon_cut_off": 2, NO_REASON: 1}
    target = issue_summary(records)
    assert target["visible_40_frames"] == 5 and target["visible_40_fixed_pct"] == 80.0
    assert target["quarter_1m_mean_mm"] == pytest.approx(21.5) and target["quarter_2m_mean_mm"] is None
    assert target["over_50mm"] == 1
    assert not any(target["met"].values())


def test_run_tabulates_every_bin_and_every_refusal_has_its_reason():
    config = PartialConfig(distances_m=(1.0,), scales=(0.1,), frames=4, seed=3)
    report = run_partial(config, workers=1)
    (cell,) = report["cells"]
    assert cell["frame"] == "388x518"
    assert [row["visible"] for row in cell["bins"]] == ["20-40", "40-60", "60-80", "80-95"]
    assert [row["frames"] for row in cell["bins"]] == [1, 1, 1, 1]  # stratified: one frame per bin here
    for row in cell["bins"]:
        assert {
            "frames",
            "coverage_pct",
            "mean_mm",
            "p95_mm",
            "max_mm",
            "over_50mm",
            "inside_95_pct",
            "ellipse_na",
            "refusals",
        } <= set(row)
    assert len(report["frames"]) == 4
    for frame in report["frames"]:
        assert BINS[0][0] <= frame["visible_share"] <= BINS[-1][1] and frame["borders"]
        if frame["ok"]:
            assert frame["error_2d_mm"] is not None
        else:
            assert frame["reason"] in {reason.value for reason in FailureReason} and frame["message"]
    assert sum(cell["all"]["refusals"].values()) == 4 - cell["all"]["fixed"]
    text = format_partial(report)
    header = text.splitlines()[1].split()
    assert header[:11] == ["frame", "dist", "visible", "frames", "cover", "mean", "p95", "max", ">50mm", "in95", "n/a"]
    assert "issue 11" in text.splitlines()[-1]


def test_cli_bench_partial_prints_json_and_writes_the_plot(tmp_path, capsys):
    argv = ["bench", "partial", "--scales", "0.1", "--distances", "2", "--frames", "2", "--workers", "1"]
    assert main([*argv, "--json", "--figures", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["config"]["frames"] == 2 and len(report["frames"]) == 2
    assert (tmp_path / "partial.png").stat().st_size > 0 and (tmp_path / "partial.json").exists()
    assert main(argv) == 0
    assert "refusals" in capsys.readouterr().out
    assert main([*argv[:-4], "--frames", "0"]) == 2
