"""Real phone photos of blinking LEDs (issue 29): `lumipose bench real-leds [--cache DIR] [--json]`.

The photos are Luxapose's (lab11/vlc-localization at commit 345192d, `processing/samples/`): a Nokia
Lumia 1020 (33 MP) under LEDs keyed fully off at 2-4 kHz. That repository has no licence, so nothing
of it is shipped here: this bench fetches the photos at run time from GitHub, pinned to that commit,
and caches them under `--cache`.

Each photo is read as an ID frame with the set's assumptions: the row time of lab11's camera model
(`phones/cameras/lumia_1020_back.py`, 47.54 kHz: ~21.0 us a row), the photos' EXIF exposure (6e-5 s),
no calibration (fx = 1.2 x width; the stripes do not need it). The portrait-stored photos hold their
stripes along the columns: they are read transposed, and as stored only for the turned hint.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from server.ingest import LumaFrame
from server.vision.beacons import blob_mask
from server.vlc.capture import frame_blobs
from server.vlc.decoder import row_time_s
from server.vlc.reader import read_id_frame
from server.vlc.stripes import NoStripes, measure_stripes, row_signal
from shared_schemas import CameraIntrinsics, FrameFormat, FrameKind, FrameMeta

REPOSITORY = "lab11/vlc-localization"
COMMIT = "345192d3265a17d0360263416888ca0fcb788b0f"
RAW_URL = f"https://raw.githubusercontent.com/{REPOSITORY}/{COMMIT}/processing/samples/{{name}}"
DEFAULT_CACHE = Path("~/.cache/lumipose/lab11")
ROW_RATE_HZ = 47.54e3  # lab11's phones/cameras/lumia_1020_back.py, rolling_shutter_r
EXPOSURE_S = 6e-5  # every photo's EXIF ExposureTime
# processing/test_pics.py reads all four in room test_rig, whose LEDs blink at these (rooms/test_rig.py)
TEST_RIG_HZ = (2000.0, 2500.0, 3000.0, 3500.0, 4000.0)


@dataclass(frozen=True)
class Photo:
    name: str
    transposed: bool  # stored portrait: its stripes run along the columns until transposed
    leds_by_eye: int


# LEDs by eye: counted by us on the coarse view (every 9th row and column, gain x4, dilated 3 px) of each
# photo, as stripes read: a striped spot is one LED
PHOTOS = (
    Photo("x_0_y_1.27.jpg", False, 5),
    Photo("small_blob.jpg", False, 5),
    Photo("2014-02-27--18-15-03-62.jpg", True, 3),
    Photo("2014-02-27--18-16-34-97.jpg", True, 4),
)


def fetch_photo(name: str, cache: Path) -> Path:
    """The cached photo `name`, fetched from `RAW_URL` when missing (a clear error naming the URL if that fails)."""
    import httpx

    path = cache.expanduser() / name
    if path.exists() and path.stat().st_size > 0:
        return path
    url = RAW_URL.format(name=name)
    print(f"fetching {url}", file=sys.stderr)
    try:
        response = httpx.get(url, follow_redirects=True, timeout=60.0)
        response.raise_for_status()
    except httpx.HTTPError as error:
        message = f"bench real-leds: cannot fetch {url} ({error}); the photos are not shipped (no licence)"
        raise SystemExit(message) from error
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(response.content)
    return path


def id_frame(pixels: np.ndarray, exposure_s: float = EXPOSURE_S, skew_s: float | None = None) -> LumaFrame:
    """`pixels` as an ID frame with the set's row time and exposure (or another frame's: `exposure_s`, and
    `skew_s` from the first row to the last)."""
    height, width = pixels.shape
    camera = CameraIntrinsics(fx=1.2 * width, fy=1.2 * width, cx=width / 2, cy=height / 2)
    meta = FrameMeta(
        format=FrameFormat.png,
        width=width,
        height=height,
        camera=camera,
        exposure_s=exposure_s,
        rolling_shutter_skew_s=(height - 1) / ROW_RATE_HZ if skew_s is None else skew_s,
        timestamp_ns=0,
        frame_kind=FrameKind.id,
    )
    pixels = np.ascontiguousarray(pixels)
    pixels.flags.writeable = False
    return LumaFrame(pixels, meta, camera)


def read_frame(frame: LumaFrame) -> dict:
    """The blobs of ID frame `frame`, each one's stripes, and what the ID reader makes of them."""
    found = frame_blobs(frame)
    row_time = row_time_s(frame.meta.rolling_shutter_skew_s or 0.0, frame.meta.height)
    exposure_s = frame.meta.exposure_s or EXPOSURE_S
    blobs = []
    for blob in found.blobs:
        y0, x0, mask = blob_mask(frame.pixels, blob, found)
        signal = row_signal(frame.pixels, mask, (y0, x0), row_time, exposure_s)
        stripes = measure_stripes(*signal, row_time, exposure_s) if signal is not None else NoStripes("too few rows")
        entry: dict = {"box": list(blob.bounding_box), "hidden_outline": blob.hidden_outline, "cut_off": blob.cut_off}
        if isinstance(stripes, NoStripes):
            entry["stripes"] = stripes.reason
        else:
            nearest = min(TEST_RIG_HZ, key=lambda f: abs(f - stripes.frequency_hz))
            entry |= {
                "frequency_hz": round(stripes.frequency_hz, 1),
                "frequency_hz_sigma": round(stripes.frequency_hz_sigma, 1),
                "duty": round(stripes.duty, 3),
                "nearest_stated_hz": nearest,
                "off_stated_pct": round(100 * (stripes.frequency_hz / nearest - 1), 2),
            }
        blobs.append(entry)
    reading = read_id_frame(frame)
    return {
        "stripe_gap_rows": found.stripe_gap_rows,
        "blobs": blobs,
        "refused": [reason.removeprefix("the brightest blob is not the beacon: ") for reason in found.rejected],
        "panels_read": len(reading.panels),
        "problem": reading.problem,
    }


def bench_real_leds(cache: Path = DEFAULT_CACHE) -> dict:
    rows = []
    for photo in PHOTOS:
        stored = cv2.imread(str(fetch_photo(photo.name, cache)), cv2.IMREAD_GRAYSCALE)
        if stored is None:
            raise SystemExit(f"bench real-leds: {cache / photo.name} is not a readable image (delete it, fetch again)")
        readable, turned = (stored.T, stored) if photo.transposed else (stored, stored.T)
        start = time.perf_counter()
        row: dict = {
            "photo": photo.name,
            "size": list(stored.shape[::-1]),
            "read_transposed": photo.transposed,
            "leds_by_eye": photo.leds_by_eye,
            "stripes_along_rows": read_frame(id_frame(readable)),
            "turned": read_frame(id_frame(turned)),
        }
        row["seconds"] = round(time.perf_counter() - start, 1)
        print(f"{photo.name}: {len(row['stripes_along_rows']['blobs'])} blobs ({row['seconds']} s)", file=sys.stderr)
        rows.append(row)
    found = sum(min(len(r["stripes_along_rows"]["blobs"]), r["leds_by_eye"]) for r in rows)
    return {
        "source": f"{REPOSITORY}@{COMMIT[:7]} processing/samples (no licence: fetched, not shipped)",
        "assumptions": {"row_time_us": round(1e6 / ROW_RATE_HZ, 2), "exposure_s": EXPOSURE_S, "room": "test_rig"},
        "stated_hz": list(TEST_RIG_HZ),
        "photos": rows,
        "leds_by_eye": sum(r["leds_by_eye"] for r in rows),
        "leds_found": found,
    }


def format_real_leds(report: dict) -> str:
    a = report["assumptions"]
    lines = [
        f"{report['source']}; row time {a['row_time_us']} us, exposure {a['exposure_s']:g} s, "
        f"room {a['room']} (stated {', '.join(f'{f:g}' for f in report['stated_hz'])} Hz)"
    ]
    for row in report["photos"]:
        read, turned = row["stripes_along_rows"], row["turned"]
        how = "transposed" if row["read_transposed"] else "as stored"
        lines.append(
            f"{row['photo']} ({how}, bridge {read['stripe_gap_rows']} rows): {len(read['blobs'])} blobs "
            f"of {row['leds_by_eye']} LEDs by eye, {read['panels_read']} panels read"
        )
        for blob in read["blobs"]:
            if "frequency_hz" in blob:
                stripes = (
                    f"{blob['frequency_hz']:.0f} +- {blob['frequency_hz_sigma']:.0f} Hz "
                    f"(stated {blob['nearest_stated_hz']:g}: {blob['off_stated_pct']:+.1f} %), duty {blob['duty']:.2f}"
                )
            else:
                stripes = blob["stripes"]
            lines.append(f"    blob {blob['box']}{' hidden outline' if blob['hidden_outline'] else ''}: {stripes}")
        lines += [f"    refused: {reason}" for reason in read["refused"]]
        lines.append(f"    turned by 90 degrees: {len(turned['blobs'])} blobs, problem: {turned['problem']}")
    lines.append(f"LEDs found as one blob each: {report['leds_found']} of {report['leds_by_eye']}")
    return "\n".join(lines)
