"""Walking a room from files (issue 15 item 2): `simulate office --bursts`, then `locate` and
`client locate` with `--device` (one session, ID frames first as the app sends them) and `--beacon-id`."""

import json
import uuid
from pathlib import Path

import pytest

from lumipose_cli.main import main
from shared_schemas import load_map
from simulator.scene import find_scene
from tests.conftest import API_KEY

CAPTURES = 2
TOLERANCE_M = 0.05  # a walk at 0.8 m/s, fifth resolution: about 20 mm


@pytest.fixture(scope="module")
def walk(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("office")
    assert main(["simulate", "office", str(folder), "--limit", str(CAPTURES), "--scale", "0.2", "--bursts",
                 "--workers", "1"]) == 0
    return folder


def _frames(folder: Path) -> list[Path]:
    return sorted(folder.glob("office_*.json"))  # as shot: each pose frame, then its ID frames


def _as_used(frames: list[Path]) -> list[Path]:
    """The order the commands send and print them: each capture's ID frames, then its pose frame."""
    return sorted(frames, key=lambda path: (path.stem.split("_")[1], path.stem.endswith("_pose")))


def _truth(path: Path) -> list[float]:
    return json.loads(path.read_text())["ground_truth"]["position_m"]


def _check_fixes(frames: list[Path], results: list[dict]) -> None:
    assert len(results) == len(frames)
    beacon_ids = {beacon.id for beacon in load_map(frames[0].parent / "map.json").beacons}
    for path, result in zip(frames, results, strict=True):
        if path.stem.endswith("_id"):
            assert result["reason"] == "id_frame", result
            continue
        assert result["ok"], result
        assert result["beacon_id"] in beacon_ids and result["beacon_id_source"] in ("vlc", "tracked")
        error_m = sum((a - b) ** 2 for a, b in zip(result["position_m"][:2], _truth(path)[:2])) ** 0.5
        assert error_m < TOLERANCE_M, (path.name, result["position_m"], _truth(path))


def test_simulate_office_labels_each_frame_as_what_it_is(walk):
    """Pose frames at the scene's pose exposure, ID frames labelled 'id' at the id_frames exposure."""
    scene = find_scene("office")
    metas = [json.loads(path.read_text()) for path in _frames(walk)]
    assert len(metas) == CAPTURES * 5
    for path, meta in zip(_frames(walk), metas, strict=True):
        kind = "id" if path.stem.endswith("_id") else "pose"
        assert meta["frame_kind"] == kind
        assert meta["exposure_s"] == (scene.id_frames.exposure_s if kind == "id" else scene.sensor.exposure_s)
    assert metas[0]["exposure_s"] > 1 / 2500 > metas[1]["exposure_s"]  # the code: averaged away / kept


def test_locate_walks_the_office_through_one_device_session(walk, capsys):
    frames = _frames(walk)
    room = ["--map", str(walk / "map.json")]
    assert main(["locate", *map(str, frames), *room, "--device", "phone", "--json"]) == 0
    _check_fixes(_as_used(frames), [json.loads(line) for line in capsys.readouterr().out.splitlines()])
    assert main(["locate", *map(str, frames), *room, "--device", "phone"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == [path.name for path in _as_used(frames)]  # one line each, as used
    assert "(1 waiting)" in lines[0] and "(4 waiting)" in lines[3]  # kept for the pose frame on the next line
    assert "beacon" in lines[4] and "truth error 2D" in lines[4]
    # without a device a pose frame cannot carry the code: no beacon ID
    assert main(["locate", str(frames[0]), *room]) == 1
    assert "unknown_beacon" in capsys.readouterr().out


def test_locate_with_a_beacon_id(walk, capsys):
    first = _frames(walk)[0]  # under beacon 17's quarter of the room
    assert main(["locate", str(first), "--map", str(walk / "map.json"), "--beacon-id", "17", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["beacon_id"] == 17
    assert sum((a - b) ** 2 for a, b in zip(result["position_m"][:2], _truth(first)[:2])) ** 0.5 < TOLERANCE_M


def test_a_beacon_id_not_in_the_map_is_bad_input(walk, capsys):
    command = ["locate", str(_frames(walk)[0]), "--map", str(walk / "map.json"), "--beacon-id", "5"]
    assert main([*command, "--json"]) == 2
    error = json.loads(capsys.readouterr().out)
    assert error["error"] == "unknown_beacon" and error["field"] == "beacon_id"
    assert "beacon 5 is not in map 'office'" in error["message"]
    assert main(command) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "beacon 5 is not in map 'office' (its beacons: 17, 42, 99, 200)" in captured.err


def test_client_locate_walks_the_office_as_the_app_sends_it(walk, server_url, capsys):
    """The service's session for a device (X-Lumipose-Device); a fresh device name, so nothing of it is
    left for another test (an idle session goes after session_idle_s)."""
    from lumipose_client import Client

    name = "office-walk-test"
    with Client(server_url, api_key=API_KEY) as client:
        client.put_map(load_map(walk / "map.json").model_copy(update={"name": name}))
    frames = _frames(walk)
    url = ["client", "--url", server_url, "locate"]
    assert main([*url, *map(str, frames), "--map", name, "--device", f"walker-{uuid.uuid4().hex[:8]}", "--json"]) == 0
    _check_fixes(_as_used(frames), [json.loads(line) for line in capsys.readouterr().out.splitlines()])
    assert main([*url, str(frames[0]), "--map", name, "--beacon-id", "17", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["beacon_id"] == 17
    assert main([*url, str(frames[0]), "--map", name, "--beacon-id", "5"]) == 2
    assert f"beacon 5 is not in map '{name}'" in capsys.readouterr().err


def test_client_locate_prints_the_walk_as_locate_does(walk, server_url, capsys):
    """One printing for the verb (issue 31): a line per frame in the order used, the same here and over HTTP."""
    from lumipose_client import Client

    name = "office-walk-lines"
    with Client(server_url, api_key=API_KEY) as client:
        client.put_map(load_map(walk / "map.json").model_copy(update={"name": name}))
    frames = list(map(str, _frames(walk)))
    assert main(["locate", *frames, "--map", str(walk / "map.json"), "--device", "phone"]) == 0
    local = capsys.readouterr().out
    device = f"walker-{uuid.uuid4().hex[:8]}"
    assert main(["client", "--url", server_url, "locate", *frames, "--map", name, "--device", device]) == 0
    assert capsys.readouterr().out == local
    assert local.splitlines()[4].startswith(_frames(walk)[0].name)  # the pose frame after the ID frames it used
