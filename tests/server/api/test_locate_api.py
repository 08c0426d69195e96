"""POST /v1/locate against the real server: every upload form gives the fixture's position."""

import asyncio
import gzip
import json

import cv2
import httpx
import numpy as np
import pytest
import zstandard

from lumipose_client import AsyncClient, LumiposeError

FRAME_HEADER = "X-Lumipose-Frame"


def _error_mm(result, meta) -> float:
    return 1000 * float(np.hypot(*(np.array(result.position_m[:2]) - meta.ground_truth.position_m[:2])))


def _post(url, data, headers, **params):
    return httpx.post(f"{url}/v1/locate", content=data, headers=headers, params=params, timeout=30)


def _headers(meta, **extra):
    return {"Content-Type": "application/octet-stream",
            FRAME_HEADER: meta.model_dump_json(by_alias=True, exclude_none=True), **extra}


def test_client_locates_the_fixture_within_2_mm(client, fixture_frame):
    meta, data = fixture_frame
    result = client.locate(data, meta)
    assert result.ok, result.message
    assert _error_mm(result, meta) < 2.0
    assert result.beacon_id == 0 and result.timing_ms["total"] > 0


@pytest.mark.parametrize("encoding", ["gzip", "zstd"])
def test_compressed_uploads(server_url, fixture_frame, encoding):
    meta, data = fixture_frame
    body = gzip.compress(data) if encoding == "gzip" else zstandard.ZstdCompressor().compress(data)
    response = _post(server_url, body, _headers(meta, **{"Content-Encoding": encoding}))
    assert response.status_code == 200 and response.json()["ok"]


def test_multipart_upload(server_url, fixture_frame):
    meta, data = fixture_frame
    response = httpx.post(f"{server_url}/v1/locate", timeout=30, files={
        "meta": (None, meta.model_dump_json(by_alias=True)), "frame": ("frame.y", data, "application/octet-stream")})
    assert response.status_code == 200 and response.json()["ok"], response.text


def test_png_upload(server_url, fixture_frame):
    meta, data = fixture_frame
    pixels = np.frombuffer(data, np.uint8).reshape(meta.height, meta.width)
    png = cv2.imencode(".png", pixels)[1].tobytes()
    response = _post(server_url, png, _headers(meta, **{"Content-Type": "image/png"}))
    assert response.status_code == 200 and response.json()["ok"], response.text


def test_padded_rows_as_camera2_gives_them(server_url, fixture_frame):
    meta, data = fixture_frame
    stride = meta.width + 30
    rows = np.frombuffer(data, np.uint8).reshape(meta.height, meta.width)
    padded = np.full((meta.height, stride), 77, np.uint8)
    padded[:, :meta.width] = rows
    body = padded.tobytes()[: -(stride - meta.width)]  # Camera2 drops the last row's padding
    response = _post(server_url, body, _headers(meta.model_copy(update={"row_stride": stride})))
    assert response.status_code == 200 and response.json()["ok"], response.text


def test_no_beacon_is_a_result_not_an_error(server_url, fixture_frame):
    meta, data = fixture_frame
    response = _post(server_url, bytes(len(data)), _headers(meta))
    assert response.status_code == 200
    assert response.json()["ok"] is False and response.json()["reason"] == "no_beacon"


def test_unknown_beacon_and_unknown_map(client, fixture_frame):
    meta, data = fixture_frame
    result = client.locate(data, meta, beacon_id=42)
    assert not result.ok and result.reason.value == "unknown_beacon"
    with pytest.raises(LumiposeError) as refused:
        client.locate(data, meta, map="nowhere")
    assert refused.value.status == 404 and refused.value.body.field == "name"


def test_async_client_runs_concurrent_requests(server_url, fixture_frame):
    meta, data = fixture_frame

    async def run():
        async with AsyncClient(server_url) as lumipose:
            return await asyncio.gather(*(lumipose.locate(data, meta) for _ in range(4)), lumipose.health())

    *results, health = asyncio.run(run())
    assert all(result.ok for result in results) and health.status == "ok"
    assert len({json.dumps(result.position_m) for result in results}) == 1  # same frame, same answer


def test_metrics_count_fixes_and_reasons(server_url, client, fixture_frame):
    meta, data = fixture_frame
    client.locate(data, meta)
    text = httpx.get(f"{server_url}/metrics").text
    assert 'lumipose_requests_total{route="/v1/locate",status="200"}' in text
    assert "lumipose_fixes_total" in text and "lumipose_pipeline_seconds_bucket" in text


def test_cropped_upload_gives_the_full_frames_fix(client, fixture_frame):
    from lumipose_client.crop import crop_frame

    meta, data = fixture_frame
    pixels = np.frombuffer(data, np.uint8).reshape(meta.height, meta.width)
    cropped_meta, cropped = crop_frame(pixels, meta)
    whole, window = client.locate(data, meta), client.locate(cropped, cropped_meta)
    assert window.ok and np.allclose(window.position_m, whole.position_m, atol=1e-6)
