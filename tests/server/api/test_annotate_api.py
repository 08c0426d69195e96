"""POST /v1/locate?annotate=1 on the session's server: a PNG, and the result in X-Lumipose-Result."""

import json

import cv2
import httpx
import numpy as np

from lumipose_cli.main import main
from lumipose_client import AnnotatedResult
from shared_schemas.api import RESULT_HEADER, result_from_header
from tests.conftest import FIXTURE

FRAME_HEADER = "X-Lumipose-Frame"


def _post(url, meta, data, **params):
    headers = {"Content-Type": "application/octet-stream",
               FRAME_HEADER: meta.model_dump_json(by_alias=True, exclude_none=True)}
    return httpx.post(f"{url}/v1/locate", content=data, headers=headers, params=params, timeout=30)


def _image(png: bytes) -> np.ndarray:
    image = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    assert image is not None
    return image


def _error_mm(result, meta) -> float:
    return 1000 * float(np.hypot(*(np.array(result.position_m[:2]) - meta.ground_truth.position_m[:2])))


def test_annotate_answers_a_png_with_the_result_in_a_header(server_url, fixture_frame):
    meta, data = fixture_frame
    response = _post(server_url, meta, data, annotate=1)
    assert response.status_code == 200 and response.headers["content-type"] == "image/png"
    result = result_from_header(response.headers[RESULT_HEADER])
    assert result.ok and _error_mm(result, meta) < 2.0
    assert len(response.headers[RESULT_HEADER]) < 8192  # far within every hop's limit for a response's head
    assert _image(response.content).shape[1] >= 600
    plain = _post(server_url, meta, data, annotate="false")  # off: the JSON result as always
    assert plain.headers["content-type"] == "application/json" and RESULT_HEADER not in plain.headers
    assert plain.json()["position_m"] == result.position_m


def test_annotate_on_a_multipart_upload_and_on_a_refused_frame(server_url, fixture_frame):
    meta, data = fixture_frame
    response = httpx.post(f"{server_url}/v1/locate", params={"annotate": "true"}, timeout=30, files={
        "meta": (None, meta.model_dump_json(by_alias=True, exclude_none=True)), "frame": ("f.y", data)})
    assert response.headers["content-type"] == "image/png" and result_from_header(response.headers[RESULT_HEADER]).ok
    dark = _post(server_url, meta, bytes(len(data)), annotate=1)
    result = result_from_header(dark.headers[RESULT_HEADER])
    assert dark.status_code == 200 and not result.ok and result.reason == "no_beacon"
    _image(dark.content)


def test_bad_annotate_values_are_refused_by_name(server_url, fixture_frame):
    meta, data = fixture_frame
    response = _post(server_url, meta, data, annotate="maybe")
    assert response.status_code == 422  # as every invalid query parameter (docs/api.md, Errors)
    body = response.json()
    assert body["error"] == "invalid_request" and body["field"] == "annotate"


def test_the_client_and_its_command_line_write_the_picture(server_url, client, fixture_frame, tmp_path, capsys):
    meta, data = fixture_frame
    answer = client.locate(data, meta, annotate=True)
    assert isinstance(answer, AnnotatedResult) and answer.result.ok and _image(answer.png).ndim == 3
    picture = tmp_path / "seen.png"
    assert main(["client", "--url", server_url, "locate", str(FIXTURE), "--annotate", str(picture), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["ok"] and captured.err == f"picture: {picture}\n"  # as `lumipose locate` says
    assert _image(picture.read_bytes()).shape[0] > 500
