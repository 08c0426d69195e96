"""`lumipose bench vlc --shape`: the ID bench on rectangles and round downlights (issue 11)."""

import json
import subprocess
import sys

import pytest

from simulator.bench_vlc import VlcConfig, bench_beacon, panel_name, plot_vlc, run_vlc


def test_the_bench_panels_of_every_shape():
    rect = bench_beacon(VlcConfig(shape="rect", side_m=1.2, distance_m=2.0), 7)
    assert rect.extent_m == (1.2, pytest.approx(0.3)) and rect.center_m == [0.0, 0.0, 2.0]
    circle = bench_beacon(VlcConfig(shape="circle", side_m=0.2), 7)
    assert circle.diameter_m == 0.2 and not circle.has_corners
    assert bench_beacon(VlcConfig(), 7).side_m == 0.174
    with pytest.raises(ValueError, match="shape"):
        bench_beacon(VlcConfig(shape="hexagon"), 7)


def test_a_round_downlight_s_id_is_read_in_the_bench(tmp_path):
    report = run_vlc(VlcConfig(shape="circle", side_m=0.2, distance_m=1.0, trials=1, max_frames=8, seed=2), workers=1)
    assert report["shape"] == "circle" and report["extent_m"] == [0.2, 0.2]
    assert report["combined"]["success_pct"] == 100.0 and report["combined"]["confident_wrong"] == 0
    assert panel_name(report) == "0.2 m circle"
    path = tmp_path / "circle.png"
    plot_vlc([report], path, "test")
    assert path.stat().st_size > 1000


def test_the_bench_command_takes_a_shape():
    out = subprocess.run([sys.executable, "-m", "lumipose_cli", "bench", "vlc", "--shape", "rect", "--sides", "1.2",
                          "--distances", "2.5", "--trials", "1", "--max-frames", "4", "--workers", "1", "--json"],
                         capture_output=True, text=True, check=True, timeout=300)
    report = json.loads(out.stdout)["vlc"][0]
    assert report["shape"] == "rect" and report["extent_m"] == [1.2, pytest.approx(0.3)]
    assert panel_name(report) == "1200 x 300 mm rect"
    assert report["combined"]["confident_wrong"] == 0


def test_the_cut_panel_bench_names_a_panel_cut_at_its_side_and_not_one_with_a_third_of_its_rows(tmp_path):
    from simulator.bench_vlc import CutConfig, plot_cut, run_cut

    side = run_cut(CutConfig(edge="side", share=0.4, trials=1, seed=1), workers=1)
    assert side["found"] == 1 and side["chips"] > 21 and side["named_pct"] == 100.0 and side["named_wrong"] == 0
    assert side["located"] == 1 and side["mean_mm"] < 5.0
    bottom = run_cut(CutConfig(edge="bottom", share=0.3, trials=1, seed=1), workers=1)
    assert bottom["found"] == 1 and bottom["chips"] < 16 and bottom["named_pct"] == 0.0 and bottom["located"] == 0
    path = tmp_path / "cut.png"
    plot_cut([side, bottom], path)
    assert path.stat().st_size > 1000
