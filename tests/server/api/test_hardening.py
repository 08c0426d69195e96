"""The reliability probe's cases replayed against a real `lumipose serve`: each answered with the
right 4xx naming the field, in bounded time, without the server's memory growing with the
attack, and the server still answering /healthz afterwards.

Memory is the server process's peak resident size (VmHWM in /proc), which only grows: the
whole module must stay under `PEAK_BOUND_MB` above the server's size after its warm-up, where
the probe saw +750 MB (a small PNG decoded as 20000 x 20000), +780 MB (a map body read before
the 401) and +1.8 GB (ID frames kept whole).
"""

from __future__ import annotations

import json
import socket
import struct
import threading
import time
import zlib
from pathlib import Path

import httpx
import numpy as np
import pytest

from lumipose_client import Client
from shared_schemas import FrameKind, FrameMeta
from simulator.local_server import LocalServer
from tests.helpers import ROOM, process_status_kib

API_KEY = "hard-key"
READ_TIMEOUT_S = 2.0
PEAK_BOUND_MB = 200.0
FIXTURE = Path(__file__).parents[2] / "fixtures" / "bench_1m.json"


@pytest.fixture(scope="module")
def server():
    with LocalServer("--api-key", API_KEY, "--read-timeout-s", str(READ_TIMEOUT_S), "--max-upload-mb", "64",
                     "--log-level", "warning") as running:
        with Client(running.url, api_key=API_KEY) as client:  # warm up: one of everything
            meta = json.loads(FIXTURE.read_text())
            client.locate(FIXTURE.with_suffix(".y").read_bytes(), FrameMeta.model_validate(meta))
            client.put_map(ROOM)
        running.baseline_kib = process_status_kib(running.pid, "VmRSS")
        yield running
        peak_mb = (process_status_kib(running.pid, "VmHWM") - running.baseline_kib) / 1024
        assert peak_mb < PEAK_BOUND_MB, f"the server's peak grew by {peak_mb:.0f} MB"
    assert "Traceback" not in running.log(), running.log()


def post(server, path: str, *, content=b"", headers=None, timeout=10.0) -> tuple[httpx.Response, float]:
    start = time.perf_counter()
    response = httpx.post(server.url + path, content=content, headers=headers or {}, timeout=timeout)
    return response, time.perf_counter() - start


def put(server, path: str, *, content=b"", headers=None, timeout=10.0) -> tuple[httpx.Response, float]:
    start = time.perf_counter()
    response = httpx.put(server.url + path, content=content, headers=headers or {}, timeout=timeout)
    return response, time.perf_counter() - start


def refused(response: httpx.Response, status: int, field: str | None) -> dict:
    assert response.status_code == status, response.text
    body = response.json()
    assert body["field"] == field, body
    return body


def still_healthy(server) -> None:
    assert httpx.get(server.url + "/healthz", timeout=5).status_code == 200


def frame_header(**changes) -> dict:
    meta = json.loads(FIXTURE.read_text())
    meta.update(changes)
    return meta


def test_a_frame_header_nested_thousands_deep_is_a_400(server):
    deep = "[" * 5000 + "]" * 5000
    header = json.dumps(frame_header())[:-1] + f', "x": {deep}}}'
    response, seconds = post(server, "/v1/locate", content=b"\0" * 10,
                             headers={"X-Lumipose-Frame": header, "Content-Type": "application/octet-stream"})
    assert refused(response, 400, None)["error"] == "bad_frame" and "recursion" in response.json()["message"]
    assert seconds < 2.0
    still_healthy(server)


def png_claiming(width: int, height: int) -> bytes:
    """A PNG of width x height black grey pixels: a few hundred kilobytes, gigabytes once decoded."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    packer, row, pieces = zlib.compressobj(9), b"\0" * (width + 1), []
    for _ in range(height):
        pieces.append(packer.compress(row))
    pieces.append(packer.flush())
    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", b"".join(pieces)) + chunk(b"IEND", b"")


def test_a_small_png_holding_a_huge_image_is_refused_before_it_is_decoded(server):
    data = png_claiming(20000, 20000)
    assert len(data) < 1_000_000
    header = json.dumps(frame_header(format="PNG", width=970, height=1296, row_stride=None))
    response, seconds = post(server, "/v1/locate", content=data,
                             headers={"X-Lumipose-Frame": header, "Content-Type": "image/png"})
    assert "20000x20000" in refused(response, 400, "width")["message"]
    assert seconds < 2.0
    still_healthy(server)


def big_body(megabytes: int):
    piece = b" " * (1 << 20)
    for _ in range(megabytes):
        yield piece


def test_a_map_without_the_key_is_refused_before_its_body_is_read(server):
    # 200 MB, chunked: the answer must come long before the body could have been sent
    response, seconds = put(server, "/v1/maps/huge", content=big_body(200),
                            headers={"Content-Type": "application/json"})
    refused(response, 401, "X-API-Key")
    assert seconds < 5.0
    response, seconds = put(server, "/v1/maps/huge", content=b" " * (78 << 20),
                            headers={"Content-Type": "application/json"})
    refused(response, 401, "X-API-Key")
    still_healthy(server)


def test_json_bodies_are_capped_with_and_without_a_length(server):
    keyed = {"Content-Type": "application/json", "X-API-Key": API_KEY}
    response, seconds = put(server, "/v1/maps/huge", content=b" " * (5 << 20), headers=keyed)
    assert refused(response, 413, "body")["error"] == "too_large" and seconds < 3.0
    response, seconds = put(server, "/v1/maps/huge", content=big_body(50), headers=keyed)
    refused(response, 413, "body")
    assert seconds < 5.0
    still_healthy(server)


def test_a_json_body_nested_thousands_deep_is_a_400(server):
    keyed = {"Content-Type": "application/json", "X-API-Key": API_KEY}
    response, _ = put(server, "/v1/maps/deep", content=b"[" * 100_000 + b"]" * 100_000, headers=keyed)
    assert refused(response, 400, "body")["error"] == "too_deep"
    still_healthy(server)


def trickle(server, head: bytes, pause_s: float = 1.0, limit_s: float = 10.0) -> tuple[bytes, float]:
    """Send `head` a byte at a time; what the server answered, and after how long it cut us off."""
    start = time.perf_counter()
    with socket.create_connection(("127.0.0.1", server.port), timeout=limit_s) as sock:
        answer = b""
        try:
            for byte in head:
                sock.sendall(bytes([byte]))
                time.sleep(pause_s)
                if time.perf_counter() - start > limit_s:
                    break
        except OSError:
            pass  # the server closed the connection: what it said is still readable
        try:
            while chunk := sock.recv(4096):
                answer += chunk
        except OSError:
            pass
    return answer, time.perf_counter() - start


def test_headers_sent_a_byte_a_second_are_cut_off(server):
    head = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: " + b"a" * 200 + b"\r\n\r\n"
    answer, seconds = trickle(server, head, pause_s=0.5)
    assert answer.startswith(b"HTTP/1.1 408"), answer[:200]
    assert READ_TIMEOUT_S <= seconds < READ_TIMEOUT_S + 2.0


def test_a_map_body_sent_a_byte_a_second_is_cut_off(server):
    body = json.dumps(ROOM.model_dump(by_alias=True)).encode()
    head = (f"PUT /v1/maps/room HTTP/1.1\r\nHost: x\r\nX-API-Key: {API_KEY}\r\nContent-Type: application/json\r\n"
            f"Content-Length: {len(body)}\r\n\r\n").encode()
    start = time.perf_counter()
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
        sock.sendall(head)
        answer = b""
        for byte in body[:20]:
            try:
                sock.sendall(bytes([byte]))
            except OSError:
                break
            time.sleep(0.25)
        sock.settimeout(5)
        while chunk := sock.recv(4096):
            answer += chunk
            if b"}" in answer:
                break
    assert answer.startswith(b"HTTP/1.1 408"), answer[:200]
    assert time.perf_counter() - start < READ_TIMEOUT_S + 3.0


def test_twenty_slow_clients_at_once_are_all_cut_off_and_others_are_served(server):
    head = b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: " + b"a" * 200 + b"\r\n\r\n"
    results: list[tuple[bytes, float]] = []
    threads = [threading.Thread(target=lambda: results.append(trickle(server, head, pause_s=0.5)))
               for _ in range(20)]
    for thread in threads:
        thread.start()
    time.sleep(0.5)
    still_healthy(server)  # served while they trickle
    for thread in threads:
        thread.join()
    assert len(results) == 20
    assert all(answer.startswith(b"HTTP/1.1 408") for answer, _ in results)
    assert max(seconds for _, seconds in results) < READ_TIMEOUT_S + 3.0


def test_request_headers_past_the_limit_are_a_431(server):
    response = httpx.get(server.url + "/healthz", headers={"X-Big": "a" * (100 << 10)}, timeout=5)
    assert response.status_code == 431 and response.json()["field"] == "headers"
    still_healthy(server)


def id_frame(seed: int) -> tuple[bytes, FrameMeta]:
    """A 4-megapixel ID frame with two striped panels (the stripes, not the pixels, must be kept)."""
    from tests.helpers import two_panel_frame

    frame = two_panel_frame(level_dn=200.0, exposure_s=1 / 8000, seed=seed, t_s=0.01 * seed)
    pixels = np.zeros((2048, 2048), np.uint8)
    pixels[: frame.pixels.shape[0], : frame.pixels.shape[1]] = frame.pixels
    meta = frame.meta.model_copy(update={"width": 2048, "height": 2048, "row_stride": None, "camera": frame.camera})
    return pixels.tobytes(), FrameMeta.model_validate(meta.model_dump(by_alias=True))


def test_id_frames_of_many_devices_hold_their_stripes_not_their_pixels(server):
    data, meta = id_frame(1)
    assert meta.frame_kind is FrameKind.id
    with Client(server.url, api_key=API_KEY) as client:
        for k in range(60):  # 15 devices x a burst of 4: 240 MB of pixels
            answer = client.locate(data, meta, map=ROOM.name, device=f"phone-{k // 4}", compress=None)
            assert answer.reason.value == "id_frame" and "kept" in answer.message, answer.message
    still_healthy(server)


def test_an_unknown_map_name_and_bad_numbers_in_the_query_are_4xx(server):
    response, _ = post(server, "/v1/locate?map=nope&beacon_id=-1", content=b"x",
                       headers={"X-Lumipose-Frame": json.dumps(frame_header()),
                                "Content-Type": "application/octet-stream"})
    assert response.status_code == 422 and response.json()["field"] == "beacon_id"


def test_one_endless_header_line_is_a_431_before_it_ends(server):
    with socket.create_connection(("127.0.0.1", server.port), timeout=5) as sock:
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Long: " + b"a" * (100 << 10))  # no end of line
        answer = sock.recv(4096)
    assert answer.startswith(b"HTTP/1.1 431"), answer[:200]


def test_a_body_nobody_reads_does_not_hold_the_connection(server):
    start = time.perf_counter()
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
        sock.sendall(b"POST /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: 100000\r\n\r\n")
        answer = b""
        for _ in range(20):  # a byte every 0.2 s: the answer is sent, then the connection must end
            try:
                sock.sendall(b"x")
                chunk = sock.recv(4096) if answer == b"" else b""
            except OSError:
                break
            answer += chunk
            time.sleep(0.2)
        sock.settimeout(3)
        try:
            while sock.recv(4096):
                pass
        except OSError:
            pass
    assert answer.startswith(b"HTTP/1.1 405"), answer[:200]
    assert time.perf_counter() - start < 6.0


def test_a_client_that_hangs_up_mid_upload_is_not_a_server_error(server):
    header = json.dumps(frame_header())
    with socket.create_connection(("127.0.0.1", server.port), timeout=5) as sock:
        sock.sendall(f"POST /v1/locate HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                     f"X-Lumipose-Frame: {header}\r\nContent-Length: 1257120\r\n\r\n".encode() + b"\0" * 1000)
        time.sleep(0.3)
    time.sleep(0.5)
    still_healthy(server)


def test_no_server_error_was_counted(server):
    metrics = httpx.get(server.url + "/metrics", timeout=5).text
    errors = [line for line in metrics.splitlines() if line.startswith("lumipose_server_errors_total")]
    assert errors == ["lumipose_server_errors_total 0.0"], errors


# Numbers within no physical range (item 1 of the issue): each refused by the contract's models,
# naming the field, before any arithmetic; the map's PUT is refused, so no locate can fail on it.
OUT_OF_RANGE_FRAMES = [
    ({"camera": {**frame_header()["camera"], "fx": 1e308}}, "camera.fx"),
    ({"camera": {**frame_header()["camera"], "cx": 1e-300, "fx": 1e-300}}, "camera.fx"),
    ({"camera": {**frame_header()["camera"], "distortion": [1e300, 0, 0, 0, 0]}}, "camera.distortion.0"),
    ({"camera": {**frame_header()["camera"], "distortion": [1e10] * 8}}, "camera.distortion.0"),
    ({"gravity_camera": [1e200, 1e200, 1e200]}, "gravity_camera.0"),
    ({"timestamp_ns": 10**400}, "timestamp_ns"),
]


def test_numbers_out_of_their_physical_range_are_4xx_naming_the_field(server):
    data = FIXTURE.with_suffix(".y").read_bytes()
    for changes, field in OUT_OF_RANGE_FRAMES:
        header = json.dumps(frame_header(**changes))
        response, seconds = post(server, "/v1/locate?gravity=always", content=data,
                                 headers={"X-Lumipose-Frame": header, "Content-Type": "application/octet-stream"})
        assert refused(response, 400, field)["error"] == "bad_frame", (changes, response.text)
        assert seconds < 5.0
    beacon = ROOM.beacons[0].model_dump()
    for changes, field in [({"side_m": 1e-300}, "beacons.0.side_m"), ({"side_m": 1e308}, "beacons.0.side_m"),
                           ({"center_m": [0.0, 0.0, 1e308]}, "beacons.0.center_m.2")]:
        body = json.dumps({"name": "tiny", "beacons": [{**beacon, **changes}]})
        response, _ = put(server, "/v1/maps/tiny", content=body.encode(),
                          headers={"X-API-Key": API_KEY, "Content-Type": "application/json"})
        assert refused(response, 422, field)["error"] == "invalid_request", response.text
    assert httpx.get(server.url + "/v1/maps/tiny", headers={"X-API-Key": API_KEY}, timeout=5).status_code == 404
    still_healthy(server)
