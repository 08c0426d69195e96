"""The environment rule: the flags that configure a deployment (every `serve` flag, `client`'s --url and
--api-key, `locate --data-dir`) read LUMIPOSE_<FLAG> when not given; no other flag reads the environment."""

import json

import pytest

from lumipose_cli.main import build_parser, main
from shared_schemas.cli import environment_name


def test_deployment_flags_read_their_variable_and_a_given_flag_wins(monkeypatch, tmp_path):
    assert environment_name("--max-upload-mb") == "LUMIPOSE_MAX_UPLOAD_MB"
    monkeypatch.setenv("LUMIPOSE_PORT", "8123")
    monkeypatch.setenv("LUMIPOSE_CORS_ORIGINS", '["http://a", "http://b"]')  # a JSON list, as Settings reads them
    monkeypatch.setenv("LUMIPOSE_URL", "http://example.invalid:9")
    monkeypatch.setenv("LUMIPOSE_API_KEY", "k")
    monkeypatch.setenv("LUMIPOSE_DATA_DIR", str(tmp_path))
    parse = build_parser().parse_args
    assert parse(["serve"]).port == 8123 and parse(["serve", "--port", "9000"]).port == 9000
    assert parse(["serve"]).cors_origins == ["http://a", "http://b"]
    for argv in (["client", "maps", "list"], ["client", "locate", "f.json"]):
        args = parse(argv)
        assert (args.url, args.api_key) == ("http://example.invalid:9", "k")
    assert parse(["client", "locate", "f.json", "--url", "http://h"]).url == "http://h"
    assert parse(["locate", "f.json"]).data_dir == tmp_path


def test_a_deployments_variables_do_not_change_other_commands(monkeypatch, capsys):
    assert main(["fov", "--json"]) == 0
    at_1m = json.loads(capsys.readouterr().out)["fov_m"][0]
    for name, value in {"LUMIPOSE_DISTANCE": "2", "LUMIPOSE_JSON": "1", "LUMIPOSE_MAP": "office",
                        "LUMIPOSE_URL": "http://deployment:8000", "LUMIPOSE_WORKERS": "8",
                        "LUMIPOSE_PROFILE": "mine.json", "LUMIPOSE_DEVICE": "phone"}.items():
        monkeypatch.setenv(name, value)
    assert main(["fov", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["fov_m"][0] == pytest.approx(at_1m)
    parse = build_parser().parse_args
    load = parse(["bench", "load"])
    assert load.url is None and load.workers == 1  # no load test sent at the deployment by accident
    assert parse(["render", "out"]).map == "test-bench"
    located = parse(["locate", "f.json"])
    assert (located.map, located.profile, located.device) == ("test-bench", [], None)


@pytest.mark.parametrize("variable, value, argv", [("LUMIPOSE_PORT", "eighty", ["serve"]),
                                                   ("LUMIPOSE_LOG_LEVEL", "loud", ["serve"])])
def test_a_bad_variable_is_bad_input_naming_it(variable, value, argv, monkeypatch, capsys):
    monkeypatch.setenv(variable, value)
    with pytest.raises(SystemExit) as exit_code:
        main([*argv, "--json"])
    assert exit_code.value.code == 2
    body = json.loads(capsys.readouterr().out)
    assert body["field"] == variable.removeprefix("LUMIPOSE_").lower() and f"{variable}='{value}'" in body["message"]
