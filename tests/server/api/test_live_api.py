"""The operator page's routes on a real server: live devices, the event stream, kept pictures, the status."""

import json
import threading
import time
import uuid

import cv2
import httpx
import numpy as np

from server.api.metrics import histogram_quantile
from lumipose_client.client import FRAME_HEADER

CORNER_GREEN = (0, 255, 0)  # BGR, as server/annotate.py draws the corners


def _device() -> str:
    return f"live-{uuid.uuid4().hex[:8]}"  # the session server is shared: a name of this test's own


def _events(response: httpx.Response):
    """(event, data) pairs of a server-sent event stream, as they arrive."""
    kind = None
    for line in response.iter_lines():
        if line.startswith("event: "):
            kind = line[len("event: "):]
        elif line.startswith("data: "):
            yield kind, json.loads(line[len("data: "):])


def test_a_devices_frame_shows_on_the_board_with_its_fix_and_picture(server_url, client, fixture_frame):
    meta, data = fixture_frame
    device = _device()
    results = [client.locate(data, meta, device=device) for _ in range(2)]
    assert all(r.ok for r in results)
    live = httpx.get(f"{server_url}/v1/live/devices").json()
    (mine,) = [d for d in live["devices"] if d["device"] == device]
    assert (mine["frames"], mine["fixes"], mine["map"]) == (2, 2, "test-bench")
    assert mine["last"]["position_m"] == results[-1].position_m and mine["last_latency_ms"] > 0
    assert len(mine["track"]) == 2 and len(mine["frames_kept"]) == 2
    frames = httpx.get(f"{server_url}/v1/live/devices/{device}/frames").json()
    assert [f["seq"] for f in frames] == mine["frames_kept"][::-1]
    x0, y0, x1, y1 = frames[0]["window_px"]
    corners = np.array(results[-1].corners_px)
    assert (x0 <= corners[:, 0]).all() and (corners[:, 0] < x1).all() and (y0 <= corners[:, 1]).all()
    png = httpx.get(f"{server_url}/v1/live/devices/{device}/frames/{frames[0]['seq']}.png")
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    image = cv2.imdecode(np.frombuffer(png.content, np.uint8), cv2.IMREAD_COLOR)
    assert (image == CORNER_GREEN).all(axis=2).sum() > 100  # the four corners' discs


def test_a_frame_without_a_device_is_not_on_the_board(server_url, client, fixture_frame):
    meta, data = fixture_frame
    before = len(httpx.get(f"{server_url}/v1/live/devices").json()["devices"])
    assert client.locate(data, meta).ok
    assert len(httpx.get(f"{server_url}/v1/live/devices").json()["devices"]) == before


def test_device_names_with_slashes_and_spaces_open_and_a_blank_header_names_no_device(
    server_url, client, fixture_frame
):
    meta, data = fixture_frame
    device = f"{_device()} lab/bench 2"
    client.locate(data, meta, device=device)
    quoted = httpx.URL(f"{server_url}/v1/live/devices/").join(device.replace(" ", "%20").replace("/", "%2F"))
    frames = httpx.get(f"{quoted}/frames")
    assert frames.status_code == 200 and len(frames.json()) == 1
    assert httpx.get(f"{quoted}/frames/{frames.json()[0]['seq']}.png").status_code == 200
    before = {d["device"] for d in httpx.get(f"{server_url}/v1/live/devices").json()["devices"]}
    blank = httpx.post(f"{server_url}/v1/locate", content=data, timeout=30, headers={
        "Content-Type": "application/octet-stream", "X-Lumipose-Device": "",
        FRAME_HEADER: meta.model_dump_json(by_alias=True, exclude_none=True)})
    assert blank.status_code == 200 and blank.json()["ok"]
    after = {d["device"] for d in httpx.get(f"{server_url}/v1/live/devices").json()["devices"]}
    assert after == before


def test_unknown_devices_and_frames_are_named_404s(server_url, client, fixture_frame):
    missing = httpx.get(f"{server_url}/v1/live/devices/nobody-{uuid.uuid4().hex}/frames")
    assert missing.status_code == 404 and missing.json()["error"] == "unknown_device"
    meta, data = fixture_frame
    device = _device()
    client.locate(data, meta, device=device)
    gone = httpx.get(f"{server_url}/v1/live/devices/{device}/frames/999999.png")
    assert gone.status_code == 404 and gone.json() == {
        "error": "unknown_frame", "field": "seq", "message": f"frame 999999 of '{device}' is no longer kept"}
    bad = httpx.get(f"{server_url}/v1/live/devices/{device}/frames/-1.png")
    assert bad.status_code in (404, 422) and bad.json()["error"]


def test_the_event_stream_pushes_a_devices_frames_and_the_status(server_url, client, fixture_frame):
    meta, data = fixture_frame
    device = _device()
    seen: list[tuple[str, dict]] = []
    with httpx.stream("GET", f"{server_url}/v1/live/events", timeout=20) as response:
        assert response.headers["content-type"].startswith("text/event-stream")
        events = _events(response)
        kind, first = next(events)
        assert kind == "devices" and "devices" in first  # everything on the board first
        poster = threading.Thread(target=lambda: [client.locate(data, meta, device=device) for _ in range(3)])
        poster.start()
        for kind, payload in events:
            seen.append((kind, payload))
            mine = [d for d in payload["devices"] if d["device"] == device] if kind == "devices" else []
            kinds = {k for k, _ in seen}
            if mine and mine[0]["frames"] == 3 and "status" in kinds:
                break
        poster.join()
    updates = [d for kind, p in seen if kind == "devices" for d in p["devices"] if d["device"] == device]
    assert sum(len(d["track"]) for d in updates) == 3  # each fix's point sent once: the page appends them
    status = next(p for kind, p in seen if kind == "status")
    assert status["version"] and status["uptime_s"] > 0


def test_status_gives_rates_and_latency_quantiles_of_the_routes(server_url, client, fixture_frame):
    meta, data = fixture_frame
    for _ in range(3):
        client.locate(data, meta)
    with httpx.stream("GET", f"{server_url}/v1/live/events", timeout=10) as response:
        next(_events(response))
    for _ in range(50):  # the server counts the stream when it notices its end (at its next event, within 2 s)
        status = httpx.get(f"{server_url}/v1/status").json()
        streams = [r for r in status["routes"] if r["route"] == "/v1/live/events"]
        if streams:
            break
        time.sleep(0.1)
    (events,) = streams
    assert events["requests"] >= 1 and events["p50_ms"] is None  # a page's stay is not a latency
    assert "id_frame" not in status["refused"]
    assert status["active_map"] == "test-bench" and status["fixes"] >= 3 and status["window_s"] > 0
    (locate,) = [r for r in status["routes"] if r["route"] == "/v1/locate"]
    assert locate["requests"] >= 3 and locate["rate_hz"] > 0
    assert 0 < locate["p50_ms"] <= locate["p90_ms"] <= locate["p99_ms"]


def test_the_page_is_served_from_the_package(server_url):
    root = httpx.get(f"{server_url}/", follow_redirects=False)
    assert root.status_code == 307 and root.headers["location"] == "/dashboard/"
    page = httpx.get(f"{server_url}/dashboard/")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html") and "<html" in page.text
    assert httpx.get(f"{server_url}/dashboard/static/no-such-file.js").status_code == 404
    metrics = httpx.get(f"{server_url}/metrics").text  # the static files counted as theirs, not "unmatched"
    assert 'lumipose_requests_total{route="/dashboard/static",status="404"}' in metrics


def test_histogram_quantiles_interpolate_within_their_bucket():
    buckets = ((0.01, 50.0), (0.02, 90.0), (0.05, 100.0), (float("inf"), 100.0))
    assert histogram_quantile(0.5, buckets) == 0.01
    assert histogram_quantile(0.7, buckets) == 0.015
    assert histogram_quantile(0.99, buckets) == 0.047
    assert histogram_quantile(0.5, ((0.01, 0.0), (float("inf"), 0.0))) is None
    assert histogram_quantile(0.9, ((0.01, 1.0), (float("inf"), 10.0))) == 0.01  # past the last bound: that bound


def test_a_server_with_a_page_open_stops_at_once(tmp_path):
    """An event stream never ends by itself: the server closes it when it stops instead of waiting for it."""
    from simulator.local_server import LocalServer

    with LocalServer("--log-level", "warning", data_dir=tmp_path) as server:
        stream = httpx.Client(timeout=10).stream("GET", f"{server.url}/v1/live/events")
        response = stream.__enter__()
        events = _events(response)
        assert next(events)[0] == "devices"
        start = time.perf_counter()
        server.process.terminate()
        server.process.wait(timeout=30)
        stopped_s = time.perf_counter() - start
    assert stopped_s < 2.5, f"the server took {stopped_s:.1f} s to stop with a page open"  # was 5-7 s
    try:  # the stream was closed, not left hanging: reading it to its end returns
        list(events)
    except httpx.RemoteProtocolError:  # closed in the middle of its (endless) body
        pass
