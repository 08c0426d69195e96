"""`lumipose client ...` against the real server: exit codes and what it prints."""

import json
import re
import shutil
from pathlib import Path

import pytest

import cv2
import numpy as np

from lumipose_cli.main import main
from lumipose_client import read_fixture_files
from shared_schemas import DEMO_MAP_PATH, load_map
from shared_schemas.api import cell_truth_m
from tests.conftest import API_KEY, FIXTURE


def _without_time(summary: str) -> str:
    return re.sub(r", [0-9.]+ ms$", "", summary, flags=re.MULTILINE)


def test_client_locate_prints_the_result(server_url, capsys):
    """As `lumipose locate` prints it (issue 31): the summary, or with --json the contract's result."""
    assert main(["locate", str(FIXTURE)]) == 0
    local = capsys.readouterr().out
    assert main(["client", "--url", server_url, "locate", str(FIXTURE)]) == 0
    served = capsys.readouterr().out
    assert served.startswith("camera ") and "\nposition  x=" in served and "\ntruth     error 2D" in served, served
    assert _without_time(served) == _without_time(local)
    assert main(["client", "--url", server_url, "locate", str(FIXTURE), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ok"]


def test_client_store_list_evaluate(server_url, capsys, tmp_path):
    assert main(["client", "--url", server_url, "samples", "store", str(FIXTURE), "--label", "3,-2"]) == 2
    assert "X-API-Key" in capsys.readouterr().err
    assert main(["client", "--url", server_url, "--api-key", API_KEY, "samples", "store", str(FIXTURE),
                 "--label", "3,-2"]) == 0
    sample_id = capsys.readouterr().out.split()[0]
    assert main(["client", "--url", server_url, "samples", "list"]) == 0
    assert sample_id in capsys.readouterr().out
    assert main(["client", "--url", server_url, "samples", "evaluate", "--figures", str(tmp_path)]) == 0
    assert "coverage 100.0 %" in capsys.readouterr().out
    assert (tmp_path / "samples_scatter.png").stat().st_size > 10_000
    assert (tmp_path / "samples_heatmap.png").stat().st_size > 5_000
    assert main(["client", "--url", server_url, "--api-key", API_KEY, "samples", "delete", sample_id]) == 0


def test_client_without_a_server_is_a_clear_error(capsys):
    assert main(["client", "--url", "http://127.0.0.1:9", "maps", "list"]) == 2
    assert "cannot reach http://127.0.0.1:9" in capsys.readouterr().err


def test_client_locate_sends_a_png_beside_a_json_that_says_y8(server_url, capsys, tmp_path):
    """The client reads a fixture as the server's `lumipose locate` does: the format of the file found."""
    meta, data = read_fixture_files(FIXTURE)
    assert meta.format.value == "Y8"
    pixels = np.frombuffer(data, np.uint8).reshape(meta.height, meta.stride)[:, :meta.width]
    shutil.copy(FIXTURE, tmp_path / "frame.json")
    (tmp_path / "frame.png").write_bytes(cv2.imencode(".png", pixels)[1].tobytes())
    assert main(["locate", str(tmp_path / "frame.json"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ok"]
    results = []
    for path in (tmp_path / "frame.json", FIXTURE):
        assert main(["client", "--url", server_url, "locate", str(path), "--json"]) == 0
        results.append(json.loads(capsys.readouterr().out))
    png, y8 = results
    assert png["ok"] and png["position_m"] == y8["position_m"]  # the same pixels, the same fix


def test_client_profiles_put_list_get_delete(server_url, capsys, tmp_path):
    from tests.helpers import CALIBRATED

    stored = CALIBRATED.model_copy(update={"id": "cli-calibrated"})
    path = tmp_path / "profile.json"
    path.write_text(stored.model_dump_json())
    url = ["client", "--url", server_url, "--api-key", API_KEY]
    assert main([*url, "profiles", "put", str(path)]) == 0
    assert "stored profile 'cli-calibrated' (3880x5184, calibrated)" in capsys.readouterr().out
    assert main([*url, "profiles", "list"]) == 0
    listed = capsys.readouterr().out
    assert "cli-calibrated    3880x5184  front  calibrated  stored " in listed
    assert "xiaomi-mi8-rear   3024x4032  rear   datasheet   bundled" in listed
    assert main([*url, "profiles", "get", "cli-calibrated"]) == 0
    assert json.loads(capsys.readouterr().out)["intrinsics"]["fx"] == stored.intrinsics.fx
    assert main([*url, "profiles", "delete", "cli-calibrated", "xiaomi-mi8-front"]) == 2
    captured = capsys.readouterr()
    assert "deleted profile cli-calibrated" in captured.out and "bundled_profile" in captured.err
    assert main([*url, "profiles", "get", "cli-calibrated"]) == 2
    assert "no device profile 'cli-calibrated'" in capsys.readouterr().err


def test_url_and_key_after_the_verb_or_from_the_environment(server_url, capsys, monkeypatch):
    assert main(["client", "locate", str(FIXTURE), "--url", server_url, "--compress", "none", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ok"]
    monkeypatch.setenv("LUMIPOSE_URL", server_url)
    monkeypatch.setenv("LUMIPOSE_API_KEY", "wrong")
    assert main(["client", "maps", "list"]) == 0
    assert "* test-bench" in capsys.readouterr().out
    assert main(["client", "--api-key", "wrong", "maps", "activate", "test-bench", "--api-key", API_KEY]) == 0
    assert capsys.readouterr().out == "active map: test-bench\n"
    assert main(["client", "maps", "activate", "test-bench"]) == 2  # the environment's key
    assert "HTTP 401 unauthorized" in capsys.readouterr().err


def test_a_negative_cell_label_is_a_value_not_a_flag(server_url, capsys):
    assert main(["client", "samples", "store", str(FIXTURE), "--label", "-8,11", "--url", server_url,
                 "--api-key", API_KEY, "--json"]) == 0
    (stored,) = json.loads(capsys.readouterr().out)
    assert stored["label"] == "-8,11" and stored["result"]["ok"]
    assert main(["client", "--url", server_url, "samples", "evaluate", "--json"]) == 0
    rows = {row["id"]: row for row in json.loads(capsys.readouterr().out)["rows"]}
    assert rows[stored["id"]]["label"] == "-8,11" and cell_truth_m("-8,11", 0.05) == pytest.approx([-0.4, 0.55, 0])
    assert main(["client", "--url", server_url, "--api-key", API_KEY, "samples", "delete", stored["id"]]) == 0


def test_json_errors_are_the_contracts_error_body(server_url, capsys, tmp_path):
    cases = [
        (["--url", "http://127.0.0.1:9", "maps", "list"], "unreachable", "url"),
        (["--url", server_url, "profiles", "get", "no-such-profile"], "not_found", "profile_id"),  # the server's
        (["--url", server_url, "maps", "put", str(tmp_path / "missing.json")], "bad_input", None),
        (["--url", server_url, "--api-key", API_KEY, "maps", "delete", "test-bench"], "active_map", "name"),
        (["--url", server_url, "locate", str(tmp_path / "missing.json")], "bad_input", None),
    ]
    for argv, error, field in cases:
        assert main(["client", *argv, "--json"]) == 2, argv
        out = capsys.readouterr().out
        body = json.loads(out)
        assert (body["error"], body["field"]) == (error, field), out
        assert body["message"]
    assert main(["client", "--url", server_url, "profiles", "get", "no-such-profile"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "error: HTTP 404 not_found: no device profile 'no-such-profile'" in captured.err


def test_map_names_or_files_and_maps_delete(server_url, capsys, tmp_path):
    url = ["--url", server_url, "--api-key", API_KEY]
    assert main(["client", "locate", str(FIXTURE), "--map", str(DEMO_MAP_PATH), *url, "--json"]) == 0  # its name
    assert json.loads(capsys.readouterr().out)["ok"]
    room = tmp_path / "cli-room.json"
    room.write_text(load_map().model_copy(update={"name": "cli-room"}).model_dump_json(by_alias=True))
    assert main(["client", "locate", str(FIXTURE), "--map", str(room), *url]) == 2
    assert f"the service has no map 'cli-room' (read from {room}): store it with `lumipose client maps put {room}`" \
        in capsys.readouterr().err
    assert main(["client", "maps", "put", str(room), *url]) == 0
    assert main(["client", "locate", str(FIXTURE), "--map", str(room), *url]) == 0
    moved = load_map().model_copy(update={"name": "cli-room", "beacons": []})
    moved.beacons.append(load_map().beacons[0].model_copy(update={"center_m": [1.0, 0.0, 1.0]}))
    edited = tmp_path / "edited.json"
    edited.write_text(moved.model_dump_json(by_alias=True))
    capsys.readouterr()
    assert main(["client", "samples", "evaluate", "--map", str(edited), *url, "--json"]) == 2
    body = json.loads(capsys.readouterr().out)
    assert body["error"] == "map_differs" and f"the service's map 'cli-room' differs from {edited}" in body["message"]
    assert main(["client", "locate", str(FIXTURE), "--map", "cli-room", *url]) == 0
    assert main(["client", "maps", "delete", "cli-room", *url]) == 0
    assert "deleted map cli-room" in capsys.readouterr().out
    assert main(["client", "maps", "delete", "test-bench", *url]) == 2
    assert "active_map" in capsys.readouterr().err


def test_one_photo_the_service_refuses_is_its_own_line_in_a_batch(server_url, capsys, tmp_path):
    """As `lumipose locate`: a damaged photo among good ones is its own line (the service's error body), the
    others are located, and the exit code says the worst (2)."""
    real = Path(__file__).parents[1] / "fixtures" / "real_photos" / "exif-jpg_hdr_canon_hdr_NO.jpg"
    good, bad = tmp_path / "a.jpg", tmp_path / "b.jpg"
    shutil.copy(real, good)
    bad.write_bytes(real.read_bytes()[:3000])  # a transfer cut short
    args = ["client", "--url", server_url, "locate", str(good), str(bad), str(good), "--camera", "3000,3000,511,383"]
    assert main([*args, "--json"]) == 2
    lines = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert len(lines) == 3 and "ok" in lines[0] and "ok" in lines[2]
    assert lines[1]["error"] == "bad_frame" and "b.jpg" in lines[1]["message"], lines[1]
    assert main(args) == 2
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 3 and out[1].startswith("b.jpg  error: "), out


def test_a_bad_camera_for_several_photos_is_one_error_for_the_call(server_url, capsys, tmp_path):
    """The service refuses `--camera` itself (400, field camera), not a photo: one error, as `lumipose locate`."""
    real = Path(__file__).parents[1] / "fixtures" / "real_photos" / "exif-jpg_hdr_canon_hdr_NO.jpg"
    args = ["client", "--url", server_url, "locate", str(real), str(real), "--camera", "3000,3000"]
    assert main([*args, "--json"]) == 2
    captured = capsys.readouterr()
    error = json.loads(captured.out or captured.err)
    assert error["error"] == "bad_frame" and error["field"] == "camera", error
    assert main(args) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("camera takes 4 to 9 numbers") == 1, captured
