"""One rule for the whole command line: a flag `--some-flag` not given reads LUMIPOSE_SOME_FLAG."""

import json

import pytest

from lumipose_cli.main import build_parser, main
from shared_schemas.cli import environment_name


def test_a_variable_is_the_flags_default_and_a_given_flag_wins(monkeypatch, capsys):
    assert environment_name("--max-upload-mb") == "LUMIPOSE_MAX_UPLOAD_MB"
    assert main(["fov", "--json"]) == 0
    at_1m = json.loads(capsys.readouterr().out)["fov_m"][0]
    monkeypatch.setenv("LUMIPOSE_DISTANCE", "2")
    monkeypatch.setenv("LUMIPOSE_JSON", "1")
    assert main(["fov"]) == 0
    assert json.loads(capsys.readouterr().out)["fov_m"][0] == pytest.approx(2 * at_1m)
    assert main(["fov", "--distance", "1"]) == 0
    assert json.loads(capsys.readouterr().out)["fov_m"][0] == pytest.approx(at_1m)


def test_lists_switches_and_paths_from_variables(monkeypatch, tmp_path):
    monkeypatch.setenv("LUMIPOSE_SCALES", "0.1 0.2")
    monkeypatch.setenv("LUMIPOSE_ENCODINGS", '["gzip", "zstd"]')  # a JSON list, as the service's settings read it
    monkeypatch.setenv("LUMIPOSE_NO_GRAVITY", "true")
    assert build_parser().parse_args(["bench", "partial"]).scales == [0.1, 0.2]
    assert build_parser().parse_args(["bench", "load"]).encodings == ["gzip", "zstd"]
    assert build_parser().parse_args(["render", "out"]).no_gravity is True
    monkeypatch.setenv("LUMIPOSE_PROFILE", str(tmp_path / "a.json"))
    assert build_parser().parse_args(["locate", "frame.json"]).profile == [tmp_path / "a.json"]  # an appended flag


@pytest.mark.parametrize("variable, value", [("LUMIPOSE_CELL", "wide"), ("LUMIPOSE_NO_GRAVITY", "maybe"),
                                             ("LUMIPOSE_FRAMES", "4k")])
def test_a_bad_variable_is_bad_input_naming_it(variable, value, monkeypatch, capsys):
    monkeypatch.setenv(variable, value)
    argv = {"LUMIPOSE_CELL": ["fov"], "LUMIPOSE_NO_GRAVITY": ["render", "out"], "LUMIPOSE_FRAMES": ["bench", "load"]}
    with pytest.raises(SystemExit) as exit_code:
        main([*argv[variable], "--json"])
    assert exit_code.value.code == 2
    body = json.loads(capsys.readouterr().out)
    assert body["field"] == variable.removeprefix("LUMIPOSE_").lower() and f"{variable}='{value}'" in body["message"]
