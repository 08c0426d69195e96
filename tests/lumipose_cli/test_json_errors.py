"""`--json` on bad input: every command prints the contract's ErrorBody on stdout and exits 2."""

import json

import pytest

from lumipose_cli.main import main
from shared_schemas import DEMO_MAP_PATH
from tests.conftest import FIXTURE


SURVEY = ["survey", str(FIXTURE), "--anchor", "0", "--out"]
CASES = {  # argv ("TMP/" is the test's folder), then the ErrorBody's error and field
    "locate frame": (["locate", "TMP/missing.json"], "bad_frame", None),
    "locate map": (["locate", str(FIXTURE), "--map", "nowhere"], "bad_input", "map"),
    "fov": (["fov", "--distance", "-1"], "bad_input", None),
    "survey map": ([*SURVEY, "TMP/map.json", "--map", "nowhere"], "bad_input", "map"),
    "survey name": ([*SURVEY, "TMP/bad name!.json", "--map", str(DEMO_MAP_PATH)], "bad_input", "name"),
    "survey labels": ([*SURVEY, "TMP/map.json", "--map", str(DEMO_MAP_PATH), "--labels", "TMP/missing.json"],
                      "bad_input", "labels"),
    "survey anchor": ([*SURVEY, "TMP/map.json", "--map", str(DEMO_MAP_PATH), "--anchor", "99"], "bad_input", "anchor"),
    "calibrate camera": (["calibrate", "camera", str(FIXTURE), "--board", "TMP/missing.json", "--device",
                          "xiaomi-mi8-front"], "bad_input", "board"),
    "bench accuracy --shape": (["bench", "accuracy", "--shape", "--frames", "0"], "bad_input", None),
    "bench partial": (["bench", "partial", "--frames", "0"], "bad_input", None),
    "bench robustness": (["bench", "robustness", "--effects", "fog"], "bad_input", None),
    "bench calibration": (["bench", "calibration", "--views", "1"], "bad_input", None),
    "bench bench-real": (["bench", "bench-real", "--profile", "TMP/missing.json", "--figures", "TMP/"], "bad_input",
                         "profile"),
    "bench load": (["bench", "load", "--clients", "0"], "bad_input", "clients"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_with_json_is_an_error_body_on_stdout(case, tmp_path, capsys):
    given, error, field = CASES[case]
    argv = [arg.replace("TMP/", f"{tmp_path}/") for arg in given]
    assert main([*argv, "--json"]) == 2, argv
    captured = capsys.readouterr()
    body = json.loads(captured.out)
    assert (body["error"], body["field"]) == (error, field), body
    assert body["message"] and "Traceback" not in captured.err
    assert main(argv) == 2  # without --json: a line on stderr, nothing on stdout
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.startswith("error: ")


def test_render_names_both_readings_of_a_bad_map(tmp_path, capsys):
    assert main(["render", str(tmp_path / "frame"), "--map", "nowhere", "--scale", "0.1"]) == 2
    assert "no map file 'nowhere', and no map named 'nowhere' bundled" in capsys.readouterr().err
    assert main(["render", str(tmp_path / "frame"), "--map", "test-bench", "--scale", "0.1"]) == 0


@pytest.mark.parametrize("argv, field", [
    (["bench", "load", "--frames", "4k"], "frames"),
    (["fov", "--beacon-side", "wide"], "beacon_side"),
    (["client", "locate"], None),
    (["locate", str(FIXTURE), "--no-such-flag"], None),
])
def test_a_usage_error_with_json_is_an_error_body_too(argv, field, capsys):
    with pytest.raises(SystemExit) as exit_code:
        main([*argv, "--json"])
    assert exit_code.value.code == 2
    captured = capsys.readouterr()
    body = json.loads(captured.out)
    assert (body["error"], body["field"]) == ("bad_input", field) and body["message"].startswith("lumipose")
    assert captured.err == ""
    with pytest.raises(SystemExit):
        main(argv)  # without --json: argparse's usage and error on stderr
    captured = capsys.readouterr()
    assert captured.out == "" and "error:" in captured.err
