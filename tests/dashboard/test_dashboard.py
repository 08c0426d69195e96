"""The operator's page (issue 16) in headless Chromium against a real service fed a walk under four panels.

Every check reads the page through the data-testid hooks of the issue's spec and compares it with the
truth of the simulated walk or with the service's own JSON.
"""

from __future__ import annotations

import json
import math
import re
import time
from pathlib import Path
from urllib.parse import urlsplit

import cv2
import httpx
import numpy as np
import pytest
from playwright.sync_api import expect

from lumipose_client import Client, read_fixture_files
from server.geometry import beacon_corners_m, beacon_to_world, camera_matrix, world_to_camera
from shared_schemas import FailureReason
from simulator.bench_office import true_beacon
from simulator.render import CameraPose
from tests.dashboard.live_room import (
    API_KEY,
    BENCH_CELL_M,
    BENCH_DARK,
    BENCH_STORED,
    DEVICES,
    SCREENSHOTS,
    TIMEOUT_MS,
    Walk,
    open_view,
    store_bench_samples,
)

FOLLOW_M = 0.04  # a marker to the walk's truth: its fixes at a fifth resolution are 3-16 mm off
REASONS = {reason.value for reason in FailureReason}


def marker_positions(page) -> dict[str, tuple[float, float]]:
    return page.evaluate("""() => Object.fromEntries([...document.querySelectorAll('[data-testid="device-marker"]')]
        .map((g) => [g.dataset.device, [Number(g.dataset.x), Number(g.dataset.y)]]))""")


def nearest_truth_m(walk: Walk, x_m: float, y_m: float) -> float:
    return min(math.dist((x_m, y_m), capture.truth_m[:2]) for capture in walk.captures)


# first: the bench's service starts before the walk's feeder keeps half a core busy
def test_bench_shows_table_2_of_the_stored_samples(page, bench):
    labels = store_bench_samples(bench.url, bench.frames)
    evaluation = httpx.get(f"{bench.url}/v1/samples/evaluation", params={"cell_m": BENCH_CELL_M}).json()
    assert evaluation["samples"] == len(BENCH_STORED) + 1 and evaluation["fixes"] == len(BENCH_STORED)

    open_view(page, bench.url, "bench")
    table = page.get_by_test_id("bench-table")
    table.locator('[data-field="samples"]').wait_for(timeout=TIMEOUT_MS)
    shown = {field: table.locator(f'[data-field="{field}"]').text_content() for field in (
        "samples", "with_truth", "fixes", "coverage", "mean_mm", "std_mm", "min_mm", "max_mm")}
    assert shown == {
        "samples": str(evaluation["samples"]), "with_truth": str(evaluation["with_truth"]),
        "fixes": str(evaluation["fixes"]), "coverage": f"{evaluation['coverage'] * 100:.1f} %",
        **{name: f"{evaluation[name]:.2f}" for name in ("mean_mm", "std_mm", "min_mm", "max_mm")},
    }
    expected = {label: "not-sampled" for label in labels} | {labels[k]: "sampled" for k in BENCH_STORED} | {
        labels[BENCH_DARK]: "no-fix"}
    cells = page.get_by_test_id("bench-cell")
    assert {cells.nth(k).get_attribute("data-cell"): cells.nth(k).get_attribute("data-state")
            for k in range(cells.count())} == expected  # the planned grid: the span of the stored cells
    errors = {row["label"]: row["error_2d_mm"] for row in evaluation["rows"] if row["error_2d_mm"] is not None}
    for label, error_mm in errors.items():
        assert float(page.locator(f'[data-testid="bench-cell"][data-cell="{label}"]').get_attribute(
            "data-error-mm")) == pytest.approx(error_mm, abs=1e-3)
    assert page.get_by_test_id("bench-scatter").get_by_test_id("bench-arrow").count() == len(errors)
    assert "magnified ×" in page.get_by_test_id("bench-magnification").text_content()

    i_low = int(labels[0].split(",")[0]) - 1
    page.get_by_test_id("bench-i-range").fill(f"{i_low}..{i_low + 9}")  # one more cell each side
    page.wait_for_function(f"() => document.querySelectorAll('[data-testid=\"bench-cell\"]').length === "
                           f"{len(labels) + 2}", timeout=TIMEOUT_MS)
    assert page.locator(f'[data-testid="bench-cell"][data-cell="{i_low},11"]').get_attribute(
        "data-state") == "not-sampled"

    downloads = []
    page.on("download", lambda download: downloads.append(download))
    page.get_by_test_id("bench-download").click()
    deadline = time.monotonic() + 10
    while len(downloads) < 2 and time.monotonic() < deadline:
        page.wait_for_timeout(100)
    assert sorted(d.suggested_filename.split("-")[2] for d in downloads) == ["heatmap", "scatter"]
    for download in downloads:
        text = Path(download.path()).read_text()
        assert text.startswith("<?xml") and "<svg" in text and 'xmlns="http://www.w3.org/2000/svg"' in text

    # errors leave no figure of the previous grid or evaluation under them
    page.get_by_test_id("bench-i-range").fill("x")
    page.wait_for_function("() => !document.querySelector('[data-testid=\"bench-cell\"]')", timeout=TIMEOUT_MS)
    assert "i range" in page.locator("#bench-error").text_content()
    assert page.get_by_test_id("bench-download").is_disabled() and table.is_visible()
    page.get_by_test_id("bench-cell-m").fill("20")  # the service takes at most 10 m
    page.get_by_test_id("bench-cell-m").dispatch_event("change")
    page.locator("#bench-body").wait_for(state="hidden", timeout=TIMEOUT_MS)
    assert "Could not evaluate" in page.locator("#bench-error").text_content()


def test_device_table_lists_other_maps_caps_rows_and_lets_rates_run_out(page, bench):
    """On the bench's service (its own live board): 51 devices in the active map and one in a copy of it."""
    bench_map = json.loads((bench.frames[0].parent / "map.json").read_text())
    headers = {"X-API-Key": API_KEY, "Content-Type": "application/json"}
    stored = httpx.put(f"{bench.url}/v1/maps/bench-copy", json={**bench_map, "name": "bench-copy"}, headers=headers)
    assert stored.status_code == 200, stored.text
    meta, data = read_fixture_files(bench.frames[0])
    with Client(bench.url, api_key=API_KEY) as client:
        for k in range(51):
            assert client.locate(data, meta, device=f"here-{k:02d}", compress=None).ok
        assert client.locate(data, meta, map="bench-copy", device="elsewhere", compress=None).ok
    window_s = httpx.get(f"{bench.url}/v1/live/devices").json()["window_s"]

    open_view(page, bench.url, "live")
    elsewhere = page.locator('[data-testid="device-row"][data-device="elsewhere"]')
    elsewhere.wait_for(timeout=TIMEOUT_MS)
    assert "in map bench-copy" in elsewhere.text_content()
    assert page.get_by_test_id("device-row").count() == 50  # the most recently seen; the 2 oldest summed up
    assert page.get_by_test_id("device-more").text_content() == "and 2 more devices"
    assert page.get_by_test_id("device-marker").count() == 51  # all but the one in another map
    assert page.locator('[data-testid="device-marker"][data-device="elsewhere"]').count() == 0
    assert float(elsewhere.locator('[data-field="fix-rate"]').text_content().split()[0]) > 0
    # no frame comes any more: once the window is past, the page shows no rate without a new event for the device
    page.wait_for_function("() => [...document.querySelectorAll('[data-testid=\"device-row\"] "
                           "[data-field=\"fix-rate\"]')].every((cell) => cell.textContent === '0.0 Hz')",
                           timeout=window_s * 1000 + TIMEOUT_MS)


def test_markers_follow_the_walk(page, live):
    open_view(page, live.url, "live")
    page.wait_for_function("() => document.querySelector('[data-testid=\"live-connection\"]').textContent === 'live'",
                           timeout=TIMEOUT_MS)
    # the active map is fetched beside the stream, not before it: "live" may show before the room is drawn
    page.wait_for_function("() => document.querySelectorAll('[data-testid=\"room-map\"] "
                           "[data-testid=\"panel\"]').length > 0", timeout=TIMEOUT_MS)
    panels = page.get_by_test_id("room-map").get_by_test_id("panel")
    assert sorted(int(panels.nth(k).get_attribute("data-beacon-id")) for k in range(panels.count())) == [
        beacon.id for beacon in live.walk.beacon_map.beacons]
    for beacon in live.walk.beacon_map.beacons:  # each panel shows its ID
        assert str(beacon.id) in page.locator(f'[data-testid="panel"][data-beacon-id="{beacon.id}"]').text_content()
    page.wait_for_function(f"() => document.querySelectorAll('[data-testid=\"device-marker\"]').length === "
                           f"{len(DEVICES)}", timeout=TIMEOUT_MS)
    seen: dict[str, set[tuple[float, float]]] = {device: set() for device in DEVICES}
    deadline = time.monotonic() + 30.0  # a capture every 1.5 s, slower on a busy machine
    while min(map(len, seen.values())) < 3 and time.monotonic() < deadline:  # each walks through three places
        for device, (x_m, y_m) in marker_positions(page).items():
            off_m = nearest_truth_m(live.walk, x_m, y_m)
            assert off_m < FOLLOW_M, (device, x_m, y_m, off_m, httpx.get(f"{live.url}/v1/live/devices").text)
            seen[device].add((x_m, y_m))
        page.wait_for_timeout(200)
    for device in DEVICES:
        assert len(seen[device]) >= 3, (device, seen[device], len(live.feeder.posted))
        marker = page.locator(f'[data-testid="device-marker"][data-device="{device}"]')
        assert marker.get_by_test_id("device-ellipse").count() == 1
        assert marker.get_by_test_id("device-track").count() == 1
        points = marker.get_by_test_id("device-track").get_attribute("points").split()
        assert len(points) >= 3


def test_device_table_shows_rates_latency_and_beacon(page, live):
    open_view(page, live.url, "live")
    rows = page.get_by_test_id("device-table").get_by_test_id("device-row")
    rows.first.wait_for(timeout=TIMEOUT_MS)
    page.wait_for_function(f"() => document.querySelectorAll('[data-testid=\"device-row\"]').length === "
                           f"{len(DEVICES)}", timeout=TIMEOUT_MS)
    board = httpx.get(f"{live.url}/v1/live/devices").json()
    assert {device["device"] for device in board["devices"]} == set(DEVICES)
    beacon_ids = {str(beacon.id) for beacon in live.walk.beacon_map.beacons}
    for device in DEVICES:
        row = page.locator(f'[data-testid="device-row"][data-device="{device}"]')
        rate = row.locator('[data-field="fix-rate"]').text_content()
        assert rate.endswith("Hz") and float(rate.split()[0]) > 0, rate
        latency = row.locator('[data-field="latency"]').text_content()
        assert latency.endswith("ms") and float(latency.split()[0]) > 0, latency
        beacon = row.locator('[data-field="beacon"]').evaluate("cell => cell.firstChild.textContent")
        assert beacon in beacon_ids, beacon
        reasons = row.locator('[data-field="refused"] [data-reason]')  # a share per reason, or "none"
        assert all(reasons.nth(k).get_attribute("data-reason") in REASONS for k in range(reasons.count()))
    with live.feeder.paused():  # rows and markers are drawn anew on each update: hold them still to click
        page.wait_for_timeout(600)  # the last update's event (at most 4 a second)
        page.locator(f'[data-testid="device-row"][data-device="{DEVICES[1]}"]').click()
        page.wait_for_url(f"**/dashboard/#frame/{DEVICES[1]}", timeout=TIMEOUT_MS)
        page.get_by_test_id("view-frame").wait_for(state="visible")
        for name in DEVICES:  # every marker takes its clicks (tracks drawn over them do not: pointer-events none)
            open_view(page, live.url, "live")
            page.locator(f'[data-testid="device-marker"][data-device="{name}"] circle.marker').click()
            page.wait_for_url(f"**/dashboard/#frame/{name}", timeout=TIMEOUT_MS)


SHOWN_FRAME_JS = """() => {
    const img = document.querySelector('[data-testid="frame-image"]');
    if (!img.complete || !img.naturalWidth || !img.src.endsWith(`/${img.dataset.seq}.png`)) return null;
    const canvas = document.createElement("canvas");
    [canvas.width, canvas.height] = [img.naturalWidth, img.naturalHeight];
    const context = canvas.getContext("2d");
    context.drawImage(img, 0, 0);
    const rgba = context.getImageData(0, 0, canvas.width, canvas.height).data;
    let green = 0;  // the corners' discs are pure green (server/annotate.py)
    for (let k = 0; k < rgba.length; k += 4) green += rgba[k] < 60 && rgba[k + 1] > 200 && rgba[k + 2] < 60;
    const text = (id) => document.querySelector(`[data-testid="${id}"]`).textContent;
    return {seq: Number(img.dataset.seq), green, beacon: text("frame-beacon"), pose: text("frame-pose"),
            reprojection: text("frame-reprojection"), ambiguity: text("frame-ambiguity"), reason: text("frame-reason")};
}"""


def shown_frame(page, seq: int) -> dict:
    """The frame view once it shows kept frame `seq` with its picture loaded."""
    page.wait_for_function(f"() => ({SHOWN_FRAME_JS})()?.seq === {seq}", timeout=TIMEOUT_MS)
    return page.evaluate(SHOWN_FRAME_JS)


def pose_of(meta) -> CameraPose:
    return CameraPose(np.array(meta.ground_truth.position_m), np.array(meta.ground_truth.rotation_wc))


def panel_corners_px(beacon, meta) -> np.ndarray:
    """The beacon's four corners (4, 2) in the frame's pixels for the frame's true pose."""
    pose = pose_of(meta)
    in_camera = world_to_camera(beacon_to_world(beacon, beacon_corners_m(beacon)), pose.position_m,
                                pose.rotation_wc)
    pixels, _ = cv2.projectPoints(in_camera, np.zeros(3), np.zeros(3), camera_matrix(meta.camera), None)
    return pixels.reshape(-1, 2)


def test_frame_view_outlines_the_panel_under_the_device(page, live):
    device = DEVICES[0]
    open_view(page, live.url, f"frame/{device}")
    with live.feeder.paused():
        kept = httpx.get(f"{live.url}/v1/live/devices/{device}/frames").json()
        newest = kept[0]
        shown = shown_frame(page, newest["seq"])
        posted = [p for p in live.feeder.posted if p.device == device and p.result.position_m == newest["result"][
            "position_m"]]
        assert posted, "the kept frame is one the feeder posted"
        meta = live.walk.captures[posted[-1].capture].pose_meta
        result = newest["result"]
        assert result["ok"], result  # every pose frame of the lap gives a fix
        under = true_beacon(list(live.walk.beacon_map.beacons), meta.camera, pose_of(meta), result["center_px"])
        assert shown["beacon"] == str(under) == str(result["beacon_id"])
        assert shown["green"] > 40, shown  # four green corner discs in the picture
        x0, y0, x1, y1 = newest["window_px"]
        corners = panel_corners_px(live.walk.beacon_map.beacon(under), meta)
        assert np.all((corners >= [x0, y0]) & (corners <= [x1, y1])), (newest["window_px"], corners)
        x, y, z = result["position_m"]
        assert f"{x:.4f}, {y:.4f}, {z:.4f}" in shown["pose"] and "yaw" in shown["pose"]
        assert shown["reprojection"] == f"{result['reprojection_error_px']:.3f} px"
        assert shown["reason"] == "—"
        thumbs = page.get_by_test_id("frame-thumb")
        assert [int(thumbs.nth(k).get_attribute("data-seq")) for k in range(thumbs.count())] == [
            frame["seq"] for frame in kept]
        if len(kept) > 1:  # an older kept frame, chosen from the strip
            thumbs.nth(len(kept) - 1).click()
            assert shown_frame(page, kept[-1]["seq"])["green"] > 40


def test_map_upload_shows_the_error_at_its_field(page, live, tmp_path):
    good = json.loads(live.walk.map_path.read_text())
    bad = {**good, "name": "office-bad", "beacons": [{**good["beacons"][0], "side_m": -0.174}, *good["beacons"][1:]]}
    bad_file = tmp_path / "office-bad.json"
    bad_file.write_text(json.dumps(bad, indent=2))
    refusal = httpx.put(f"{live.url}/v1/maps/office-bad", content=bad_file.read_bytes(),
                        headers={"X-API-Key": API_KEY, "Content-Type": "application/json"})
    assert refusal.status_code == 422 and refusal.json()["field"] == "beacons.0.side_m", refusal.text

    open_view(page, live.url, "maps")
    page.locator('[data-testid="map-row"][data-map="office"][data-active="true"]').wait_for(timeout=TIMEOUT_MS)
    page.get_by_test_id("map-upload").set_input_files(str(bad_file))
    expect(page.get_by_test_id("map-name")).to_have_value("office-bad", timeout=TIMEOUT_MS)  # the file's name
    page.get_by_test_id("map-name").fill("office bad/1")  # the service's names: letters, digits, _ . -
    assert "letters, digits" in page.get_by_test_id("map-name-error").text_content()
    page.get_by_test_id("map-submit").click()
    assert "name" in page.get_by_test_id("map-message").text_content()
    page.get_by_test_id("map-name").fill("office-bad")
    assert page.get_by_test_id("map-name-error").text_content() == ""
    page.get_by_test_id("map-submit").click()
    message = page.get_by_test_id("map-message")
    page.wait_for_function("() => document.querySelector('[data-testid=\"map-message\"]').textContent.includes("
                           "'needs the API key')", timeout=TIMEOUT_MS)
    assert page.get_by_test_id("map-errors").is_hidden()  # without the key nothing was judged

    page.fill("#api-key", API_KEY)
    page.get_by_test_id("map-submit").click()
    marked = page.get_by_test_id("map-error-field")
    marked.wait_for(timeout=TIMEOUT_MS)
    assert marked.get_attribute("data-field") == "beacons.0.side_m"
    assert '"side_m": -0.174' in marked.text_content()
    assert refusal.json()["message"] in marked.text_content()
    assert page.locator('[data-testid="map-errors"] .line').count() > 20  # the whole upload, pretty printed

    good_file = tmp_path / "office-copy.json"
    good_file.write_text(json.dumps({**good, "name": "office-copy"}))
    page.get_by_test_id("map-upload").set_input_files(str(good_file))
    page.get_by_test_id("map-submit").click()
    page.locator('[data-testid="map-row"][data-map="office-copy"]').wait_for(timeout=TIMEOUT_MS)
    assert "office-copy" in message.text_content() and page.get_by_test_id("map-errors").is_hidden()
    try:
        page.locator('[data-testid="map-row"][data-map="office-copy"]').click()
        page.get_by_test_id("map-activate").click()
        page.locator('[data-testid="map-row"][data-map="office-copy"][data-active="true"]').wait_for(
            timeout=TIMEOUT_MS)
        assert httpx.get(f"{live.url}/v1/maps/active").json()["name"] == "office-copy"
        assert page.get_by_test_id("map-view").get_by_test_id("map-panel").count() == len(good["beacons"])
    finally:
        httpx.put(f"{live.url}/v1/maps/active", json={"name": "office"}, headers={"X-API-Key": API_KEY})


def test_health_shows_the_version_and_the_locate_rate(page, live):
    open_view(page, live.url, "health")
    version = httpx.get(f"{live.url}/healthz").json()["version"]
    page.wait_for_function(f"() => document.querySelector('[data-testid=\"health-version\"]').textContent === "
                           f"{json.dumps(version)}", timeout=TIMEOUT_MS)
    locate = page.locator('[data-testid="health-routes"] tr[data-route="/v1/locate"]')
    locate.wait_for(timeout=TIMEOUT_MS)
    rate = locate.locator("td").nth(2).text_content()
    assert rate.endswith("/s") and float(rate.split()[0]) > 0, rate
    p50 = locate.locator("td").nth(3).text_content()
    assert p50.endswith("ms") and float(p50.split()[0]) > 0, p50
    assert page.get_by_test_id("health-map").text_content() == "office"
    assert page.get_by_test_id("health-devices").text_content() == str(len(DEVICES))
    assert re.fullmatch(r"\d\d:\d\d:\d\d", page.get_by_test_id("health-uptime").text_content())


def test_every_view_stays_on_the_server_and_logs_no_error(page, page_record, live):
    open_view(page, live.url, "live")
    page.locator('[data-testid="device-marker"]').first.wait_for(timeout=TIMEOUT_MS)
    for view in ("frame", "bench", "maps", "health", "live"):
        page.get_by_test_id(f"tab-{view}").click()
        page.get_by_test_id(f"view-{view}").wait_for(state="visible")
        page.wait_for_timeout(500)  # its requests go out
    page.get_by_test_id("frame-image").wait_for(state="attached")
    assert page.get_by_test_id("live-connection").text_content() == "live"
    paths = {urlsplit(url).path for url in page_record.requests}
    assert {"/dashboard/", "/v1/live/events", "/v1/samples/evaluation", "/v1/maps", "/v1/status"} <= paths, paths
    assert any(path.endswith(".png") for path in paths), paths  # a kept frame's picture
    assert page_record.foreign_requests() == []
    assert unexpected_console_errors(page_record) == [], page_record.failed


def unexpected_console_errors(record) -> list[str]:
    """The console's errors but the browser's own line for a kept picture dropped between the page's listing
    and its fetch (404 `unknown_frame`, the spec's answer for a frame no longer kept: a device's newest three
    frames are kept, a new one every 1.5 s)."""
    dropped = [line for line in record.failed if re.fullmatch(r"404 GET .*/v1/live/devices/.+/frames/\d+\.png", line)]
    missing = "Failed to load resource: the server responded with a status of 404 (Not Found)"
    lines = list(record.console_errors)
    for _ in dropped:
        if missing in lines:
            lines.remove(missing)
    return lines


READABLE_PX = 12.0  # the smallest tick label readable on the page at a laptop's 1400 px (issue 31)
WIDE = {"width": 1400, "height": 900}


def label_sizes(page, figure: str, labels: str = "text") -> list[dict]:
    """Each label (`labels`, a selector) of the SVG `figure` (data-testid) as the screen shows it: its font size
    in CSS px (the text's own size times the figure's scale to the screen), its box's height, px, and whether
    that box lies inside the figure's (a label cut by the figure's edge is not read either)."""
    return page.evaluate("""([figure, labels]) => {
        const svg = document.querySelector(`[data-testid="${figure}"]`);
        const [scale, frame] = [svg.getScreenCTM().a, svg.getBoundingClientRect()];
        return [...svg.querySelectorAll(labels)].map((text) => {
            const box = text.getBoundingClientRect();
            return {
                text: text.textContent,
                font_px: parseFloat(getComputedStyle(text).fontSize) * scale,
                box_px: box.height,
                inside: box.left >= frame.left - 1 && box.right <= frame.right + 1 && box.top >= frame.top - 1
                    && box.bottom <= frame.bottom + 1,
            };
        });
    }""", [figure, labels])


def test_axis_labels_are_readable_at_1400_px(browser, live, bench):
    """Every figure's axis labels (the room map's also its scale bar and device names) at least 12 CSS px on a
    1400 px wide window and inside the figure, and the room map's still at 1100 px: they keep their size on
    screen."""
    context = browser.new_context(viewport=WIDE)
    try:
        page = context.new_page()
        open_view(page, live.url, "live")
        page.get_by_test_id("room-map").locator(".tick").first.wait_for(timeout=TIMEOUT_MS)
        sizes = {"room-map": label_sizes(page, "room-map", ".tick, .axis-name, .scalebar text, .device-label")}
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        page.get_by_test_id("room-map").screenshot(path=str(SCREENSHOTS / "room-map-1400px.png"))
        scale = "document.querySelector('[data-testid=\"room-map\"]').getScreenCTM().a"
        wide_scale = page.evaluate(scale)
        page.set_viewport_size({"width": 1100, "height": 900})  # still two columns (one below 1000 px)
        page.wait_for_function(f"() => {scale} < {wide_scale * 0.9}", timeout=TIMEOUT_MS)
        sizes["room-map at 1100 px"] = label_sizes(page, "room-map", ".tick, .axis-name")
        page.set_viewport_size(WIDE)
        open_view(page, live.url, "maps")
        page.locator('[data-testid="map-row"][data-map="office"]').click()
        page.get_by_test_id("map-view").get_by_test_id("map-panel").first.wait_for(timeout=TIMEOUT_MS)
        sizes["map-view"] = label_sizes(page, "map-view", ".tick, .axis-name, .scalebar text")
        if not httpx.get(f"{bench.url}/v1/samples/evaluation").json()["samples"]:
            store_bench_samples(bench.url, bench.frames)  # this test run alone: figures need samples
        open_view(page, bench.url, "bench")
        page.get_by_test_id("bench-cell").first.wait_for(timeout=TIMEOUT_MS)
        for figure in ("bench-heatmap", "bench-scatter"):
            sizes[figure] = label_sizes(page, figure)
    finally:
        context.close()
    for figure, labels in sizes.items():
        assert labels, figure
        unread = [label for label in labels
                  if label["font_px"] < READABLE_PX or label["box_px"] < READABLE_PX or not label["inside"]]
        assert unread == [], figure
