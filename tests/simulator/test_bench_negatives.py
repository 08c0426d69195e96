"""`lumipose bench negatives` plumbing on small frames (its figures are CLI runs, docs/reliability.md)."""

import json

from lumipose_cli.main import main
from simulator.bench_negatives import NegativesConfig, panels, summarize_row, wrong_map_sample, wrong_maps


def test_every_panel_has_its_right_map_first_and_every_wrong_map_differs_from_it():
    rows = wrong_maps()
    drawn = panels()
    for key in drawn:
        mine = [row for row in rows if row.truth == key]
        assert mine[0].label == "right map" and mine[0].mapped == drawn[key].beacon
        assert all(row.mapped != drawn[key].beacon for row in mine[1:])
    assert len({row.key for row in rows}) == len(rows)
    radii = [row.mapped.corner_radius_m for row in rows if row.truth == "square-174" and "radius" in row.key]
    assert all(0 <= r < 0.087 for r in radii)  # every wrong radius is a panel's


def test_the_right_map_fixes_its_frame_within_its_ellipse():
    row = wrong_maps()[0]
    sample = wrong_map_sample((NegativesConfig(frames=1, scale=0.2, photos=None), row, 0))
    assert sample["ok"], sample
    assert sample["error_2d_m"] < 0.005 and sample["mahalanobis2"] < 13.8  # 99.9 % of chi-square, 2 dof


def test_a_row_counts_refusals_fixes_and_coverage():
    samples = [
        {"ok": False, "reason": "shape_mismatch", "message": "m"},
        {"ok": True, "error_2d_m": 0.002, "mahalanobis2": 1.0, "sigma_2d_m": 0.001},
        {"ok": True, "error_2d_m": 0.200, "mahalanobis2": 900.0, "sigma_2d_m": 0.001},
        {"ok": True, "error_2d_m": 0.004},
    ]
    row = summarize_row(samples)
    assert row["refused_pct"] == 25.0 and row["fixed_pct"] == 75.0
    assert row["refusals"] == {"shape_mismatch": 1}
    assert row["inside_95_pct"] == 50.0  # of the two fixes with an ellipse
    assert row["max_mm"] == 200.0


def test_the_command_prints_json(capsys, monkeypatch):
    # two rows only, one frame each: the CLI's plumbing, not the figures
    monkeypatch.setattr("simulator.bench_negatives.wrong_maps", lambda: wrong_maps()[:2])
    code = main(["bench", "negatives", "--frames", "1", "--scale", "0.2", "--no-photos", "--workers", "1", "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert list(report["wrong_maps"]) == [row.key for row in wrong_maps()[:2]]
    assert report["photos"] is None


def test_bad_flags_are_named(capsys):
    assert main(["bench", "negatives", "--frames", "0", "--json"]) == 2
    assert "--frames" in json.loads(capsys.readouterr().out)["message"]
