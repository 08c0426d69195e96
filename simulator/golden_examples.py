"""Golden examples from a real run: `python -m simulator.golden_examples`.

`shared_schemas/examples/` holds the contract's JSON that the Python tests validate and the
Android core's GoldenExamplesTest reads. The examples of the capture protocol are not typed in
but taken from one rendered capture of the office walk (`simulator.bench_office`) sent as the
app sends it: the ID frames whole, the pose frame cut to the beacon's window by the Python client
(`lumipose_client.crop`), all through the server's pipeline with one device's session.

- `frame_id.json`: the burst's first ID frame (`frame_kind` id, 1/8000 s, rolling-shutter skew);
- `frame_cropped.json`: the pose frame cut to the window (the `crop` block);
- `result_vlc_track.json`: the server's answer to it: `vlc`, `track`, `beacons_in_view`,
  `corners_px` (in the window's pixels), `ambiguity_ratio`, `timing_ms`.

A test renders them again and fails when they differ (timings: their keys only).
"""

from __future__ import annotations

import json
from pathlib import Path

from lumipose_client.crop import crop_frame
from server.ingest import decode_frame
from server.locator import locate
from server.tracking.devices import Devices
from shared_schemas import PACKAGE_DIR, FrameMeta
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures

EXAMPLES_DIR = PACKAGE_DIR / "examples"
CONFIG = OfficeConfig(walk="zigzag", max_captures=12, inset_m=0.5, pose_scale=0.25, seed=2)
DEVICE_ID = "golden-phone"


def _as_sent(meta: FrameMeta) -> dict:
    """The metadata as a phone sends it: no simulator truth, no empty fields."""
    return json.loads(meta.model_dump_json(by_alias=True, exclude_none=True, exclude={"ground_truth"}))


def rendered_examples() -> dict[str, dict]:
    """File name -> JSON of each example, from the first capture whose fix carries a VLC reading and a
    track and comes from a whole panel (corners and an ambiguity ratio)."""
    beacon_map = office_scenes(CONFIG)[0].beacon_map()
    devices = Devices()
    for capture in walk_captures(CONFIG):
        for id_frame in capture.id_frames:
            locate(id_frame, beacon_map, device_id=DEVICE_ID, devices=devices)
        cropped_meta, cropped = crop_frame(capture.pose_frame.pixels, capture.pose_frame.meta)
        result = locate(decode_frame(cropped, cropped_meta), beacon_map, device_id=DEVICE_ID, devices=devices)
        if result.ok and None not in (result.vlc, result.track, result.ambiguity_ratio):
            return {
                "frame_id.json": _as_sent(capture.id_frames[0].meta),
                "frame_cropped.json": _as_sent(cropped_meta),
                "result_vlc_track.json": json.loads(result.model_dump_json(by_alias=True)),
            }
    raise RuntimeError(f"no capture of {CONFIG} gave a whole panel's fix with a VLC reading and a track")


def write_examples(examples: dict[str, dict], folder: Path = EXAMPLES_DIR) -> None:
    for name, data in examples.items():
        (folder / name).write_text(json.dumps(data, indent=2) + "\n")
        print(f"wrote {folder / name}")


if __name__ == "__main__":
    write_examples(rendered_examples())
