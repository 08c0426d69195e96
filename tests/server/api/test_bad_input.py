"""Hand-made bad requests: each is a 4xx naming the problem, never a 5xx, a crash or a hang."""

import gzip
import json
import zlib

import httpx
import pytest

from tests.conftest import UPLOAD_LIMIT_MB

FRAME_HEADER = "X-Lumipose-Frame"


def _meta_json(meta, **changes) -> str:
    data = json.loads(meta.model_dump_json(by_alias=True, exclude_none=True))
    for dotted, value in changes.items():
        target, *path = data, *dotted.split("__")
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    return json.dumps(data)


def _cases(meta, data):
    """name -> (headers, body, expected status, expected field or None)."""
    raw = {"Content-Type": "application/octet-stream"}
    good = _meta_json(meta)
    huge = UPLOAD_LIMIT_MB * 1024 * 1024 + 1
    bomb = zlib.compressobj(9, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    bomb_body = bomb.compress(bytes(huge * 2)) + bomb.flush()
    return {
        "truncated frame": ({**raw, FRAME_HEADER: good}, data[:-1000], 400, "frame"),
        "wrong row stride": ({**raw, FRAME_HEADER: _meta_json(meta, row_stride=meta.width + 8)}, data, 400,
                             "row_stride"),
        "stride below width": ({**raw, FRAME_HEADER: _meta_json(meta, row_stride=meta.width - 1)}, data, 400,
                               "row_stride"),
        "zero width": ({**raw, FRAME_HEADER: _meta_json(meta, width=0)}, data, 400, "width"),
        "NaN focal length": ({**raw, FRAME_HEADER: _meta_json(meta, camera__fx=float("nan"))}, data, 400,
                             "camera.fx"),
        "infinite heading": ({**raw, FRAME_HEADER: _meta_json(meta, heading_deg=float("inf"))}, data, 400,
                             "heading_deg"),
        "negative focal length": ({**raw, FRAME_HEADER: _meta_json(meta, camera__fx=-5.0)}, data, 400, "camera.fx"),
        "unknown format": ({**raw, FRAME_HEADER: _meta_json(meta, format="RGB565")}, data, 400, "format"),
        "unknown profile": ({**raw, FRAME_HEADER: _meta_json(meta, camera={"profile": "nokia-3310"})}, data, 400,
                            "camera.profile"),
        "metadata not JSON": ({**raw, FRAME_HEADER: "{not json"}, data, 400, None),
        "metadata missing": (raw, data, 400, FRAME_HEADER),
        "wrong content type": ({"Content-Type": "text/plain", FRAME_HEADER: good}, data, 415, "Content-Type"),
        "no content type": ({FRAME_HEADER: good}, data, 415, "Content-Type"),
        "unknown encoding": ({**raw, FRAME_HEADER: good, "Content-Encoding": "br"}, data, 415, "Content-Encoding"),
        "gzip that is not": ({**raw, FRAME_HEADER: good, "Content-Encoding": "gzip"}, data[:5000], 400,
                             "Content-Encoding"),
        "truncated gzip": ({**raw, FRAME_HEADER: good, "Content-Encoding": "gzip"}, gzip.compress(data)[:-100], 400,
                           "Content-Encoding"),
        "zip bomb": ({**raw, FRAME_HEADER: good, "Content-Encoding": "gzip"}, bomb_body, 413, "body"),
        "huge upload": ({**raw, FRAME_HEADER: good}, bytes(huge), 413, "body"),
        "PNG that is not": ({"Content-Type": "image/png", FRAME_HEADER: good}, data[:1000], 400, "frame"),
        "multipart without frame": ({"Content-Type": "multipart/form-data; boundary=xx", FRAME_HEADER: good},
                                    b"--xx\r\nContent-Disposition: form-data; name=\"meta\"\r\n\r\n{}\r\n--xx--\r\n",
                                    400, "frame"),
        "multipart garbage": ({"Content-Type": "multipart/form-data; boundary=xx"}, b"garbage", 400, None),
    }




@pytest.fixture(scope="module")
def cases(fixture_frame):
    return _cases(*fixture_frame)


def test_every_bad_frame_gets_a_4xx_naming_the_problem(server_url, cases):
    failures = []
    for name, (headers, body, status, field) in cases.items():
        response = httpx.post(f"{server_url}/v1/locate", content=body, headers=headers, timeout=30)
        problem = None
        if response.status_code != status:
            problem = f"status {response.status_code}, wanted {status}: {response.text[:200]}"
        elif set(response.json()) != {"error", "field", "message"} or not response.json()["message"]:
            problem = f"body is not an ErrorBody: {response.text[:200]}"
        elif field is not None and response.json()["field"] != field:
            problem = f"field {response.json()['field']!r}, wanted {field!r}: {response.json()['message']}"
        if problem:
            failures.append(f"{name}: {problem}")
    assert not failures, "\n".join(failures)
    assert len(cases) >= 20


def test_bad_query_parameters_are_422(server_url, fixture_frame):
    meta, data = fixture_frame
    headers = {"Content-Type": "application/octet-stream", FRAME_HEADER: meta.model_dump_json(by_alias=True)}
    for params, field in (({"beacon_id": 300}, "beacon_id"), ({"gravity": "sideways"}, "gravity")):
        response = httpx.post(f"{server_url}/v1/locate", content=data, headers=headers, params=params)
        assert response.status_code == 422 and response.json()["field"] == field, response.text


def test_unknown_route_and_method_are_json_errors(server_url):
    assert httpx.get(f"{server_url}/v2/nothing").json()["error"] == "not_found"
    response = httpx.delete(f"{server_url}/v1/locate")
    assert response.status_code == 405 and response.json()["error"] == "method_not_allowed"
