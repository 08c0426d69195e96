"""Benchmark plumbing: scenes, tables and report files (small frames; the figures are CLI runs)."""

import json
import math

import numpy as np
import pytest

from lumipose_cli.main import main
from simulator.bench_fidelity import fidelity_row
from simulator.bench_grid import RealBench, grid_scene, real_bench_scene
from simulator.bench_sweeps import distance_scene, tilt_scene
from simulator.reports import Outcome, failures, table
from simulator.sampling import series_poses
from simulator.scene import find_scene


def _outcome(index, error_m, reason=None):
    estimate = None if reason else (error_m, 0.0, 0.0)
    return Outcome(index, f"({index}, 0)", (0.0, 0.0, 0.0), estimate, reason, reason and "why", 0.01)


def test_table_counts_outliers_against_coverage_as_the_paper_does():
    outcomes = [_outcome(0, 0.001), _outcome(1, 0.003), _outcome(2, 0.2), _outcome(3, 0, "beacon_cut_off")]
    summary = table(outcomes)
    assert summary["coverage_pct"] == 50.0 and summary["outliers"] == 1 and summary["no_fix"] == 1
    assert summary["mean_mm"] == pytest.approx(2.0) and summary["max_mm"] == pytest.approx(3.0)
    assert summary["refusals"] == {"beacon_cut_off": 1}
    assert [f["index"] for f in failures(outcomes)] == [2, 3]


def test_real_bench_keeps_the_datasheet_grid_but_sees_through_a_longer_distorting_lens():
    grid, real = grid_scene(), real_bench_scene()
    grid_xy = [p.position_m[:2] for p in series_poses(grid)]
    real_poses = series_poses(real)
    np.testing.assert_allclose([p.position_m[:2] for p in real_poses], grid_xy, atol=1e-12)
    assert [p.label for p in real_poses] == [p.label for p in series_poses(grid)]
    assert real.camera.intrinsics().fx == pytest.approx(grid.camera.intrinsics().fx * 1.05)
    assert real.camera.intrinsics().distortion == list(RealBench().distortion)
    pitches = np.array([p.ypr_deg[1] for p in real_poses])
    assert abs(pitches.mean() - 0.4) < 0.1 and np.ptp(pitches) <= 1.0


def test_sweep_scenes():
    base = find_scene("paper-bench")
    far = distance_scene(base, 2.5)
    assert far.beacons[0].center_m == [0.0, 0.0, 2.5] and len(series_poses(far)) == 25
    tilted = series_poses(tilt_scene(base, 10.0))
    assert len(tilted) == 36
    axes = np.array([p.camera_pose().rotation_wc[:, 2] for p in tilted[:4]])  # optical axes, 4 directions
    np.testing.assert_allclose(np.degrees(np.arccos(axes[:, 2])), 10.0, atol=1e-9)
    np.testing.assert_allclose(np.sign(axes[:, :2].round(6)), [[1, 0], [0, 1], [-1, 0], [0, -1]])


def test_fidelity_of_an_unclipped_panel_is_one():
    row = fidelity_row(2.0, 0.8)
    assert row["exact_px"] == pytest.approx(3011.4 * 0.174 / 2.0, rel=1e-3)
    assert row["ratio"] == pytest.approx(1.0, abs=5e-4)
    assert fidelity_row(2.0, 4.0)["ratio"] > 1.003  # the clipped edge's 50 % level lies outside


def test_cli_bench_grid_writes_table_and_figures(tmp_path, capsys):
    assert main(["bench", "grid", "--figures", str(tmp_path), "--scale", "0.25", "--limit", "5", "--workers", "1"]) == 0
    printed = capsys.readouterr().out
    assert "mean error" in printed and "paper        mean 7.49 mm" in printed
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["summary"]["samples"] == 5 and math.isfinite(report["summary"]["mean_mm"])
    assert (tmp_path / "paper-bench-scatter.png").stat().st_size > 10_000
    assert (tmp_path / "paper-bench-heatmap.png").stat().st_size > 10_000
    assert len(json.loads((tmp_path / "outcomes.json").read_text())) == 5


def test_cli_bench_grid_on_any_scene_file(tmp_path, capsys):
    bench = find_scene("paper-bench")
    scene = bench.model_validate({**bench.model_dump(by_alias=True), "name": "mine",
                                  "camera": {"profile": "xiaomi-mi8-front", "scale": 0.25},
                                  "series": {"path": {"kind": "poses", "poses": [{"position_m": [0.1, 0.1, 0.0]},
                                                                                 {"position_m": [-0.2, 0.0, 0.0]}]}}})
    (tmp_path / "mine.json").write_text(scene.to_json())
    assert main(["bench", "grid", "--scene", str(tmp_path / "mine.json"), "--figures", str(tmp_path / "r"),
                 "--workers", "1"]) == 0
    report = json.loads((tmp_path / "r" / "report.json").read_text())
    assert report["scene"] == "mine" and report["summary"]["samples"] == 2 and "paper" not in report
    assert (tmp_path / "r" / "mine-scatter.png").exists()
    assert not (tmp_path / "r" / "mine-heatmap.png").exists()  # explicit poses are no grid


def test_yaw_jitter_turns_the_phone_within_its_bound_only():
    yaw = np.array([p.ypr_deg for p in series_poses(grid_scene(yaw_jitter_deg=1.0))])
    assert np.abs(yaw[:, 0]).max() <= 1.0 and np.ptp(yaw[:, 0]) > 1.5 and not yaw[:, 1:].any()


def test_a_moving_camera_is_also_compared_with_where_it_was_when_the_panel_was_read():
    from simulator.reports import LocateJob, locate_sample

    walk = find_scene("walk-one-panel")
    walk = walk.model_copy(update={"camera": walk.camera.model_copy(update={"scale": 0.25})})
    sample = series_poses(walk)[2]  # on the first leg, 0.8 m/s east
    outcome = locate_sample(LocateJob(walk, sample))
    seen = (np.array([0.0, 0.0, 2.72]) - sample.position_m) @ sample.camera_pose().rotation_wc  # panel, camera frame
    row = walk.camera.intrinsics().cy + 977.78 * seen[1] / seen[2]
    tau = row * 0.03 / 1295 + 0.001 / 2
    assert outcome.at_panel_rows_m[0] == pytest.approx(sample.position_m[0] + 0.8 * tau, abs=1e-4)
    assert math.isfinite(table([outcome])["at_panel_rows"].get("mean_mm", math.nan)) or outcome.estimate_m is None


def test_a_pipeline_crash_is_recorded_not_raised(monkeypatch):
    from simulator import reports

    def broken(*args, **kwargs):
        raise ArithmeticError("nan somewhere")

    monkeypatch.setattr(reports, "locate", broken)
    scene = grid_scene(scale=0.1)
    outcome = reports.locate_sample(reports.LocateJob(scene, series_poses(scene)[0]))
    assert outcome.reason == "pipeline_error" and "nan somewhere" in outcome.message
    assert table([outcome])["refusals"] == {"pipeline_error": 1}
