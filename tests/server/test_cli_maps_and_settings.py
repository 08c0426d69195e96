"""`--map` a file or a map's name (locate, serve), and `serve`'s flags as LUMIPOSE_<FLAG> variables."""

import argparse
import json
import shutil

from lumipose_cli.main import build_parser, main
from server.api.config import Settings
from shared_schemas import DEMO_MAP_NAME, DEMO_MAP_PATH, bundled_maps, load_map
from tests.conftest import FIXTURE


def _command(*path: str) -> argparse.ArgumentParser:
    parser = build_parser()
    for name in path:
        subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = subparsers.choices[name]
    return parser


def test_the_bundled_map_names(tmp_path):
    assert bundled_maps() == {DEMO_MAP_NAME: DEMO_MAP_PATH}


def test_locate_map_is_a_file_or_a_stored_or_bundled_name(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("LUMIPOSE_DATA_DIR", raising=False)
    moved = load_map().model_copy(update={"name": "moved"})
    moved.beacons[0] = moved.beacons[0].model_copy(update={"center_m": [1.0, 0.0, 1.0]})
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / "moved.json").write_text(moved.model_dump_json(by_alias=True))
    shutil.copy(DEMO_MAP_PATH, tmp_path / "demo-copy.json")

    x_by_map = {}
    for argv in (["--map", "test-bench"], ["--map", str(tmp_path / "demo-copy.json")], [],
                 ["--map", "moved", "--data-dir", str(tmp_path)]):
        assert main(["locate", str(FIXTURE), "--json", *argv]) == 0, argv
        x_by_map[" ".join(argv)] = json.loads(capsys.readouterr().out)["position_m"][0]
    assert len({round(x, 6) for x in x_by_map.values()}) == 2  # the stored map moved the panel 1 m
    assert x_by_map["--map moved --data-dir " + str(tmp_path)] > 1.0

    monkeypatch.setenv("LUMIPOSE_DATA_DIR", str(tmp_path))
    assert main(["locate", str(FIXTURE), "--map", "moved"]) == 0
    capsys.readouterr()
    assert main(["locate", str(FIXTURE), "--map", "nowhere", "--json"]) == 2
    body = json.loads(capsys.readouterr().out)
    assert body == {"error": "bad_input", "field": "map", "message": (
        f"no map file 'nowhere', and no map named 'nowhere' stored in {tmp_path / 'maps'} or bundled "
        "(maps: moved, test-bench)")}


def test_serve_map_is_a_file_or_a_name_and_a_bad_one_stops_it(tmp_path, capsys):
    (tmp_path / "maps").mkdir()
    room = load_map().model_copy(update={"name": "room"})
    (tmp_path / "maps" / "room.json").write_text(room.model_dump_json(by_alias=True))
    assert Settings(map="room", data_dir=tmp_path).map == tmp_path / "maps" / "room.json"
    assert Settings(map="test-bench", data_dir=tmp_path).map == DEMO_MAP_PATH
    assert main(["serve", "--data-dir", str(tmp_path), "--map", "lobby"]) == 2
    assert capsys.readouterr().err == (f"error: no map file 'lobby', and no map named 'lobby' stored in "
                                       f"{tmp_path / 'maps'} or bundled (maps: room, test-bench)\n")
    assert main(["serve", "--data", str(tmp_path), "--port", "70000"]) == 2  # --data: the old name, kept
    assert capsys.readouterr().err == "error: port: Input should be less than or equal to 65535 (got 70000)\n"


def test_every_serve_flag_is_a_setting_read_from_lumipose_flag(monkeypatch):
    """One rule: the flag --some-flag is the variable LUMIPOSE_SOME_FLAG (Settings' env_prefix and field)."""
    serve = _command("serve")
    flags = [action for action in serve._actions if action.dest != "help"]
    assert len(flags) >= 15
    for action in flags:
        assert action.dest in Settings.model_fields, action.option_strings
        visible = [flag for flag in action.option_strings if action.help != argparse.SUPPRESS]
        for flag in visible:
            assert flag.removeprefix("--").replace("-", "_") == action.dest, flag
    assert Settings.model_config["env_prefix"] == "LUMIPOSE_"
    monkeypatch.setenv("LUMIPOSE_MAX_DEVICES", "7")
    monkeypatch.setenv("LUMIPOSE_LOG_LEVEL", "debug")
    assert (Settings().max_devices, Settings().log_level) == (7, "debug")
    assert Settings(max_devices=9).max_devices == 9  # a flag given wins
    assert "LUMIPOSE_SOME_FLAG" in serve.format_help()


def test_serve_redis_is_a_redis_url_and_a_bad_one_stops_it(monkeypatch, capsys):
    assert Settings().redis is None  # without it nothing is shared through Redis
    monkeypatch.setenv("LUMIPOSE_REDIS", "redis://cache:6380/2")
    assert Settings().redis == "redis://cache:6380/2"
    assert main(["serve", "--redis", "cache:6379"]) == 2
    assert capsys.readouterr().err == ("error: redis: a Redis URL starts with one of redis://, rediss://, unix:// "
                                       "(got 'cache:') (got 'cache:6379')\n")
