"""`bench results` compare: a changed decision or a move over 0.01 mm fails, a smaller move passes (no bench run)."""

import json

from simulator.bench_results import compare_runs, format_comparison, selected

CODE = {"commit": "abc1234", "dirty": False, "server_tree": "1234567", "shared_schemas_tree": "7654321"}


def _frame(key, ok=True, x_m=0.1, reason=None, beacon_id=0):
    decision = {"ok": ok, "reason": reason, "beacon_id": beacon_id if ok else None}
    return {"frame": key, "decision": decision, "positions_m": {"fix": [x_m, 0.2, 0.0]} if ok else {},
            "figures": {}}


def _results(*frames, mean_mm=1.0):
    run = {"bench": "accuracy", "params": {}, "frames": list(frames), "figures": {"1m auto mean_mm": mean_mm},
           "wall_s": 1.0}
    return {"mode": "quick", "code": CODE, "runs": {"accuracy-full": run}}


BASE = _results(_frame("1m/0/auto"), _frame("1m/1/auto", ok=False, reason="no_beacon"))


def test_a_move_under_the_tolerance_passes_and_one_over_it_fails():
    small = compare_runs(BASE, _results(_frame("1m/0/auto", x_m=0.1 + 0.005e-3),
                                        _frame("1m/1/auto", ok=False, reason="no_beacon")))
    assert small["ok"] and 0.004 < small["cases"]["accuracy-full"]["max_move_mm"] < 0.006
    large = compare_runs(BASE, _results(_frame("1m/0/auto", x_m=0.1 + 0.02e-3),
                                        _frame("1m/1/auto", ok=False, reason="no_beacon"), mean_mm=1.02))
    case = large["cases"]["accuracy-full"]
    assert not large["ok"] and case["moved"] == ["1m/0/auto"] and case["figures"]["1m auto mean_mm"] == [1.0, 1.02]
    text = format_comparison({**large, "wall_s": 1.0})
    assert "1 frames moved by more than 0.01 mm" in text and "results CHANGED" in text and "1.0000 -> 1.0200" in text


def test_a_changed_decision_fails_and_is_listed():
    now = _results(_frame("1m/0/auto"), _frame("1m/1/auto", ok=False, reason="pose_ambiguous"))
    report = compare_runs(BASE, now)
    changed = report["cases"]["accuracy-full"]["changed"]
    assert not report["ok"] and [c["frame"] for c in changed] == ["1m/1/auto"]
    assert changed[0]["before"]["reason"] == "no_beacon" and changed[0]["after"]["reason"] == "pose_ambiguous"
    assert "1m/1/auto" in format_comparison({**report, "wall_s": 1.0})
    # a fix that became a refusal is a decision, whatever its position
    assert not compare_runs(BASE, _results(_frame("1m/0/auto", ok=False, reason="no_beacon"),
                                           _frame("1m/1/auto", ok=False, reason="no_beacon")))["ok"]


def test_identical_results_pass_and_missing_frames_fail():
    assert compare_runs(BASE, json.loads(json.dumps(BASE)))["ok"]
    fewer = compare_runs(BASE, _results(_frame("1m/0/auto")))
    assert not fewer["ok"] and fewer["cases"]["accuracy-full"]["missing"] == ["1m/1/auto"]


def test_a_bench_that_failed_fails_its_case():
    report = compare_runs(BASE, {**BASE, "runs": {"accuracy-full": {"bench": "accuracy", "error": "ValueError: x"}}})
    assert not report["ok"] and "FAILED (ValueError: x)" in format_comparison({**report, "wall_s": 1.0})


def test_an_unconfident_vlc_guess_is_no_decision_a_confident_id_is():
    def trial(single, combined):
        run = {"bench": "vlc", "frames": [{"frame": "3m/0", "decision": {"id": 7, "single": single,
                                                                         "combined": combined},
                                           "positions_m": {}, "figures": {}}], "figures": {}}
        return {"mode": "quick", "code": CODE, "runs": {"vlc": run}}

    base = trial([149, False], [7, True, 5])
    guess = compare_runs(base, trial([169, False], [7, True, 5]))
    assert guess["ok"] and guess["cases"]["vlc"]["guesses_changed"] == ["3m/0"]
    assert not compare_runs(base, trial([149, False], [8, True, 5]))["ok"]  # a confident ID changed
    assert not compare_runs(base, trial([149, False], [7, True, 6]))["ok"]  # one more frame needed


def test_a_case_only_one_side_has_is_listed_not_compared():
    extra = {"bench": "photos", "params": {}, "frames": [_frame("a.jpg/square-600/1", ok=False, reason="x")],
             "figures": {}, "wall_s": 1.0}
    report = compare_runs(BASE, {**BASE, "runs": {**BASE["runs"], "photos": extra}})
    assert report["ok"] and report["not_in_baseline"] == ["photos"] and "photos" not in report["cases"]
    assert "cases not in the baseline (run, not compared): photos" in format_comparison({**report, "wall_s": 1.0})
    report = compare_runs({**BASE, "runs": {**BASE["runs"], "photos": extra}}, BASE)
    assert report["ok"] and report["not_run"] == ["photos"]


def test_luxapose_photos_only_from_a_cache_the_shipped_real_frames_always(tmp_path, capsys):
    without = {c.bench for c in selected("quick", None)}
    assert "real-leds" not in without and {"photos", "rolling-shutter"} <= without
    assert "--real-leds-cache" in capsys.readouterr().err
    (cached,) = selected("full", ["real-leds"], tmp_path)
    assert cached.params["cache"] == str(tmp_path)

