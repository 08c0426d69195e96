"""The VLC and office benches run end to end on a few samples (figures are made elsewhere)."""

import json
import subprocess
import sys

from simulator.bench_office import summarize_walk
from simulator.bench_vlc import VlcConfig, plot_vlc, run_vlc


def test_vlc_bench_reports_single_and_combined_rates(tmp_path):
    report = run_vlc(VlcConfig(distance_m=1.0, trials=2, max_frames=6, seed=3), workers=1)
    assert report["combined"]["success_pct"] == 100.0
    assert report["single"]["confident_wrong"] == report["combined"]["confident_wrong"] == 0
    assert 1 <= report["combined"]["mean_frames"] <= 6
    assert 10 < report["single"]["chips_per_frame"] < 14  # 0.174 m at 1 m: about half a message
    path = tmp_path / "vlc.png"
    plot_vlc([report], path, "test")
    assert path.stat().st_size > 1000


def test_vlc_bench_reads_an_led_that_switches_fully_off():
    # depth 1.0: separate bars with dark rows between them (before issue 29: no blob, no ID in any frame)
    report = run_vlc(VlcConfig(distance_m=1.0, trials=2, max_frames=6, seed=3, depth=1.0), workers=1)
    assert report["depth"] == 1.0
    assert report["combined"]["success_pct"] == 100.0 and report["combined"]["confident_wrong"] == 0
    assert report["combined"]["mean_captures"] == 1.0  # within one burst of 4 ID frames


def test_vlc_bench_command_prints_json(tmp_path):
    out = subprocess.run([sys.executable, "-m", "lumipose_cli", "bench", "vlc", "--distances", "2.0", "--trials", "1",
                          "--max-frames", "10", "--workers", "1", "--json", "--figures", str(tmp_path),
                          "--depth", "1.0"], capture_output=True, text=True, check=True, timeout=300)
    printed = json.loads(out.stdout)
    report = printed["vlc"][0]
    assert report["distance_m"] == 2.0 and report["trials"] == 1 and report["depth"] == 1.0
    # --figures DIR: the figure's path in the JSON and on stderr (stdout stays the JSON)
    assert printed["figures"] == [str(tmp_path / "vlc-distance.png")] and (tmp_path / "vlc-distance.png").exists()
    assert f"figure {tmp_path / 'vlc-distance.png'}" in out.stderr


def test_walk_summary_counts_coverage_id_errors_and_transitions():
    def record(t, ok, nearest, beacon=None, true=None, error=None):
        r = {"t_s": t, "truth_m": [0, 0, 1.3], "ok": ok, "reason": None if ok else "beacon_cut_off",
             "nearest_beacon": nearest}
        if ok:
            r.update({"fix_m": [0, 0, 1.3], "beacon_id": beacon, "true_beacon": true, "error_mm": error,
                      "source": "vlc", "filtered_m": [0.001, 0, 1.3]})
        return r

    records = [record(0.0, True, 1, 1, 1, 2.0), record(0.5, True, 1, 1, 1, 4.0), record(1.0, False, 2),
               record(1.5, True, 2, 1, 2, 1200.0)]
    summary = summarize_walk(records)
    assert summary["coverage_pct"] == 75.0
    assert summary["id_errors"] == 1
    assert summary["transition_captures"] == 2  # the captures on either side of the change of beacon
    assert summary["refusals"] == {"beacon_cut_off": 1}
    assert summary["fixes"]["max_mm"] == 1200.0


def test_a_trial_s_map_holds_the_panel_or_its_one_bit_neighbour():
    from simulator.bench_vlc import trial_map

    assert trial_map(VlcConfig(), 0, 42) == ((), False)  # no map: all 256 alike
    config = VlcConfig(map_ids=4, foreign_share=0.5)
    maps = [trial_map(config, index, 42) for index in range(20)]
    assert {foreign for _, foreign in maps} == {True, False}
    for ids, foreign in maps:
        assert len(set(ids)) == 4 and (42 in ids) is not foreign
        assert not foreign or any(bin(i ^ 42).count("1") == 1 for i in ids)
