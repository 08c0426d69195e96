"""The quickstart's sample photo (samples/panel-photo.jpg) and its truth, as a phone writes a photo.

`python -m simulator.sample_photo [DIR]` renders the panel of docs/quickstart.md's step-1 map (`my-panel`: a
0.6 m panel 1 m above the origin) with the Mi 8's rear camera at a quarter of its resolution, and stores it as
the phone does: the sensor's landscape rows with EXIF orientation 6 (shown upright: a quarter turn clockwise),
the make and model that name the bundled profile 'xiaomi-mi8-rear', its focal length and exposure. The truth
(the camera's pose in the map frame) goes beside it as `panel-photo.truth.json`, which `lumipose locate
--truth` reads. Rendered here, no one else's content: the files are the project's own.
"""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from PIL.TiffImagePlugin import IFDRational

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from shared_schemas import BeaconMap, device_profiles
from simulator.render import CameraPose, SensorModel, render_frame

SAMPLES_DIR = Path(__file__).resolve().parents[1] / "samples"
PROFILE = "xiaomi-mi8-rear"
SCALE = 0.25
POSITION_M = (0.1, 0.2, 0.0)
YPR_DEG = (5.0, 2.0, -1.0)
# docs/quickstart.md, step 1 (tests/test_quickstart.py checks that the page shows this map)
MY_PANEL = BeaconMap.model_validate(
    {
        "schema": "lumipose.map/1",
        "name": "my-panel",
        "beacons": [{"id": 0, "center_m": [0.0, 0.0, 1.0], "yaw_deg": 0.0, "side_m": 0.6, "corner_radius_m": 0.01}],
    }
)
STORED_ORIENTATION = 6  # the rear camera's landscape rows, held upright
JPEG_QUALITY = 92
# EXIF tag numbers (TIFF/EXIF 2.32)
MAKE, MODEL, ORIENTATION, SOFTWARE, DATE_TIME, COPYRIGHT = 0x010F, 0x0110, 0x0112, 0x0131, 0x0132, 0x8298
EXIF_IFD = 0x8769
EXPOSURE_TIME, F_NUMBER, ISO, DATE_TIME_ORIGINAL, FOCAL_LENGTH = 0x829A, 0x829D, 0x8827, 0x9003, 0x920A
PIXEL_X, PIXEL_Y, FOCAL_35MM = 0xA002, 0xA003, 0xA405
TAKEN = "2026:12:02 09:00:00"


def render_upright() -> np.ndarray:
    """The upright (portrait) luma the phone's screen shows: (height, width) uint8."""
    profile = device_profiles()[PROFILE]
    width, height = round(profile.width * SCALE), round(profile.height * SCALE)
    camera = intrinsics_from_profile(profile, width, height)
    pose = CameraPose(np.array(POSITION_M), rotation_from_ypr(*YPR_DEG))
    return render_frame(MY_PANEL.beacons[0], camera, pose, width, height, SensorModel(psf_sigma_px=1.0,
                        plateau_dn=255.0 * 4), np.random.default_rng(0))


def phone_exif(stored_width: int, stored_height: int) -> Image.Exif:
    """What a Mi 8 writes (the tags the service reads, and a few more), for a stored landscape image."""
    profile = device_profiles()[PROFILE]
    exif = Image.Exif()
    exif[MAKE], exif[MODEL], exif[ORIENTATION] = "Xiaomi", "MI 8", STORED_ORIENTATION
    exif[SOFTWARE], exif[DATE_TIME] = "lumipose simulator.sample_photo (rendered)", TAKEN
    exif[COPYRIGHT] = "the Lumipose project (rendered, no third-party content)"
    shot = exif.get_ifd(EXIF_IFD)
    shot[EXPOSURE_TIME], shot[F_NUMBER], shot[ISO] = IFDRational(1, 100), IFDRational(9, 5), 100
    shot[DATE_TIME_ORIGINAL] = TAKEN
    shot[FOCAL_LENGTH] = IFDRational(round(profile.focal_length_m * 1e5), 100)  # 4.22 mm, rounded as phones do
    shot[FOCAL_35MM] = 27
    shot[PIXEL_X], shot[PIXEL_Y] = stored_width, stored_height
    return exif


def sample_photo() -> tuple[bytes, dict]:
    """The JPEG's bytes and its truth (the pose the frame was rendered from, the map, the camera)."""
    upright = render_upright()
    stored = np.rot90(upright, 1)  # orientation 6 turns it a quarter clockwise: back to upright
    image, buffer = Image.fromarray(np.ascontiguousarray(np.stack([stored] * 3, axis=-1))), io.BytesIO()
    image.save(buffer, "JPEG", quality=JPEG_QUALITY, exif=phone_exif(stored.shape[1], stored.shape[0]))
    truth = {
        "about": "the pose samples/panel-photo.jpg was rendered from (python -m simulator.sample_photo), in the map "
        "frame of docs/quickstart.md's step-1 map; the photo and this file are the Lumipose project's own",
        "map": MY_PANEL.model_dump(by_alias=True, exclude_defaults=False, mode="json"),
        "camera": f"{PROFILE} at {SCALE} of its resolution, stored with EXIF orientation {STORED_ORIENTATION}",
        "position_m": list(POSITION_M),
        "yaw_pitch_roll_deg": list(YPR_DEG),
        "rotation_wc": rotation_from_ypr(*YPR_DEG).tolist(),
    }
    return buffer.getvalue(), truth


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else SAMPLES_DIR
    out.mkdir(parents=True, exist_ok=True)
    data, truth = sample_photo()
    (out / "panel-photo.jpg").write_bytes(data)
    (out / "panel-photo.truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    print(f"wrote {out / 'panel-photo.jpg'} ({len(data) // 1000} kB) and {out / 'panel-photo.truth.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
