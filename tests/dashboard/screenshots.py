"""The figures of docs/dashboard.md: each view of the operator's page in the live room of the browser tests.

    PYTHONPATH=$PWD .venv/bin/python -m tests.dashboard.screenshots [--out docs/figures]

writes dashboard-live.png, -frame.png, -bench.png, -maps.png and -health.png (1280 x 860, headless Debian
Chromium) from a real `lumipose serve` fed the walk of tests/dashboard/live_room.py, a second one holding
the paper's bench with stored samples, and a map upload with a bad field.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from tests.dashboard.live_room import (
    API_KEY,
    DEVICES,
    TIMEOUT_MS,
    Feeder,
    chromium,
    open_view,
    render_bench,
    render_walk,
    start_server,
    store_bench_samples,
)

FIGURES = Path(__file__).resolve().parents[2] / "docs" / "figures"
TRACK_POINTS = 6  # fixes drawn on each device's track before the live view is shot


def shoot_live(page, url: str) -> None:
    open_view(page, url, "live")
    page.wait_for_function(
        f"() => [...document.querySelectorAll('[data-testid=\"device-track\"]')].filter((line) => "
        f"line.getAttribute('points').split(' ').length >= {TRACK_POINTS}).length === {len(DEVICES)}",
        timeout=4 * TIMEOUT_MS,
    )


def shoot_frame(page, url: str) -> None:
    open_view(page, url, f"frame/{DEVICES[0]}")
    page.wait_for_function("() => [...document.querySelectorAll('[data-testid=\"frame-image\"], "
                           "[data-testid=\"frame-thumb\"] img')].every((img) => img.complete && img.naturalWidth)",
                           timeout=TIMEOUT_MS)


def shoot_maps(page, url: str, bad_map: Path) -> None:
    open_view(page, url, "maps")
    page.get_by_test_id("map-row").first.wait_for(timeout=TIMEOUT_MS)
    page.fill("#api-key", API_KEY)
    page.get_by_test_id("map-upload").set_input_files(str(bad_map))
    page.get_by_test_id("map-submit").click()
    page.get_by_test_id("map-error-field").wait_for(timeout=TIMEOUT_MS)


def shoot_health(page, url: str) -> None:
    open_view(page, url, "health")
    page.locator('[data-testid="health-routes"] tr[data-route="/v1/locate"]').wait_for(timeout=TIMEOUT_MS)


def shoot_bench(page, url: str) -> None:
    open_view(page, url, "bench")
    page.get_by_test_id("bench-cell").first.wait_for(timeout=TIMEOUT_MS)


def bad_map_file(map_path: Path, folder: Path) -> Path:
    """The room's map with its second panel's side negative, as an operator might mistype it."""
    beacon_map = json.loads(map_path.read_text())
    beacon_map["name"] = "office-draft"
    beacon_map["beacons"][1]["side_m"] = -0.174
    path = folder / "office-draft.json"
    path.write_text(json.dumps(beacon_map, indent=2))
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=FIGURES, help="folder for the PNGs (default: docs/figures)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="lumipose-dashboard-") as temporary:
        work = Path(temporary)
        walk = render_walk(work)
        bench_frames = render_bench(work / "bench")
        with start_server(work / "live-data", walk.map_path) as live, start_server(
            work / "bench-data", work / "bench" / "map.json"
        ) as bench, chromium() as browser:
            store_bench_samples(bench.url, bench_frames)
            feeder = Feeder(live.url, walk).start()
            try:
                page = browser.new_context(viewport={"width": 1280, "height": 860}).new_page()
                views = [("live", lambda: shoot_live(page, live.url)), ("frame", lambda: shoot_frame(page, live.url)),
                         ("bench", lambda: shoot_bench(page, bench.url)),
                         ("maps", lambda: shoot_maps(page, live.url, bad_map_file(walk.map_path, work))),
                         ("health", lambda: shoot_health(page, live.url))]
                for name, show in views:
                    show()
                    path = args.out / f"dashboard-{name}.png"
                    page.screenshot(path=str(path))
                    print(path)
            finally:
                feeder.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
