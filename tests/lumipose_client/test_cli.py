"""`lumipose client ...` against the real server: exit codes and what it prints."""

import json
import shutil

import cv2
import numpy as np

from lumipose_cli.main import main
from lumipose_client import read_fixture_files
from tests.conftest import API_KEY, FIXTURE


def test_client_locate_prints_the_result(server_url, capsys):
    assert main(["client", "--url", server_url, "locate", str(FIXTURE)]) == 0
    assert '"ok": true' in capsys.readouterr().out


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
        assert main(["client", "--url", server_url, "locate", str(path)]) == 0
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
    assert "cli-calibrated  3880x5184  front  calibrated  (stored)" in listed
    assert "xiaomi-mi8-rear  3024x4032  rear  datasheet  (bundled)" in listed
    assert main([*url, "profiles", "get", "cli-calibrated"]) == 0
    assert json.loads(capsys.readouterr().out)["intrinsics"]["fx"] == stored.intrinsics.fx
    assert main([*url, "profiles", "delete", "cli-calibrated", "xiaomi-mi8-front"]) == 2
    captured = capsys.readouterr()
    assert "deleted profile cli-calibrated" in captured.out and "bundled_profile" in captured.err
    assert main([*url, "profiles", "get", "cli-calibrated"]) == 2
    assert "no device profile 'cli-calibrated'" in capsys.readouterr().err
