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
    assert main(["client", "--url", server_url, "samples", "evaluate", "--plots", str(tmp_path)]) == 0
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
