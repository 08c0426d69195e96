"""What `lumipose` says on bad files, a busy port and small numbers (issue 15 item 6)."""

import json
import re
import socket
from pathlib import Path

import pytest

from lumipose_cli.main import main
from shared_schemas import DEMO_MAP_PATH

FIXTURE = Path(__file__).parent.parent / "fixtures" / "bench_1m.json"
BAD_MAP = {"name": "bad", "beacons": [{"id": 1, "center_m": [0, 0, 2], "side_m": -1}]}


@pytest.fixture
def bad_map(tmp_path) -> Path:
    path = tmp_path / "map.json"
    path.write_text(json.dumps(BAD_MAP))
    return path


def _one_short_line(err: str) -> str:
    assert err.count("\n") == 1 and "pydantic.dev" not in err and "validation error for" not in err, err
    return err


def test_a_bad_map_names_the_file_and_the_field(bad_map, tmp_path, capsys):
    for command in (["locate", str(FIXTURE)], ["render", str(tmp_path / "frame")], ["serve"]):
        assert main([*command, "--map", str(bad_map)]) == 2
        err = _one_short_line(capsys.readouterr().err)
        assert f"{bad_map}: beacons.0.side_m: Input should be greater than" in err and "(got -1)" in err


def test_a_bad_scene_profile_or_labels_file_names_the_field(tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text('{"schema": "lumipose.scene/1", "name": "s", "seed": "x"}')
    assert main(["simulate", str(scene), str(tmp_path / "out")]) == 2
    assert f"cannot read the scene {scene}: " in _one_short_line(capsys.readouterr().err)

    profile = tmp_path / "profile.json"
    profile.write_text('{"id": "p"}')
    assert main(["client", "--url", "http://127.0.0.1:9", "profiles", "put", str(profile)]) == 2
    assert f"{profile}: " in _one_short_line(capsys.readouterr().err)
    assert main(["bench", "bench-real", "--profile", str(profile), "--figures", str(tmp_path / "r")]) == 2
    assert f"--profile {profile}: " in _one_short_line(capsys.readouterr().err)

    labels = tmp_path / "labels.json"
    labels.write_text('{"f.json": [{"beacon_id": "one"}]}')
    survey = ["survey", "f.json", "--map", str(DEMO_MAP_PATH), "--anchor", "0", "--labels", str(labels)]
    assert main([*survey, "--out", str(tmp_path / "map.json")]) == 2
    assert f"cannot read labels {labels}: f.json.0." in _one_short_line(capsys.readouterr().err)


def test_client_maps_put_names_the_field_before_any_request(bad_map, capsys):
    assert main(["client", "--url", "http://127.0.0.1:9", "maps", "put", str(bad_map)]) == 2
    assert f"{bad_map}: beacons.0.side_m" in _one_short_line(capsys.readouterr().err)


def test_serve_on_a_busy_port_says_so_and_announces_nothing(capsys):
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        port = holder.getsockname()[1]
        assert main(["serve", "--port", str(port)]) == 2
    captured = capsys.readouterr()
    assert captured.err == f"error: port {port} is in use on 127.0.0.1 (another server? give --port)\n"
    assert "serving" not in captured.out + captured.err


def test_the_ambiguity_ratio_prints_with_the_digits_it_has(capsys):
    assert main(["locate", str(FIXTURE), "--json"]) == 0
    ratio = json.loads(capsys.readouterr().out)["ambiguity_ratio"]
    assert main(["locate", str(FIXTURE)]) == 0
    printed = re.search(r"ambiguity ratio (\S+),", capsys.readouterr().out)
    assert printed is not None and float(printed.group(1)) == pytest.approx(ratio, rel=0.05), (printed, ratio)
