"""Write the capture protocol both sides read: `python -m lumipose_cli.capture_protocol`.

`shared_schemas/capture_protocol.json` holds the numbers the phone needs to take frames the
server can read (the beacons' code, the burst, the exposures, the server's ID-exposure limit)
and to cut the same beacon window as the Python client, with the full frame's levels
(`shared_schemas.windows`). They are read here from the modules
that use them, so the file cannot drift from the server or the client; the Android core reads
the file (`io.lumipose.client.protocol.CaptureProtocol`). This module sits above both the
server and the client (tests/test_layering.py). A test fails when the file is stale.
"""

from __future__ import annotations

import json

from lumipose_client import crop
from server.vlc import capture
from server.vlc.codec import CHIP_RATE_HZ, MESSAGE_CHIPS
from shared_schemas import PACKAGE_DIR, windows

PROTOCOL_SCHEMA = "lumipose.capture_protocol/1"
PROTOCOL_PATH = PACKAGE_DIR / "capture_protocol.json"


def capture_protocol() -> dict[str, object]:
    """The protocol's values, from the constants the server and the client use."""
    return {
        "schema": PROTOCOL_SCHEMA,
        "chip_rate_hz": CHIP_RATE_HZ,
        "message_chips": MESSAGE_CHIPS,
        "golden_step": capture.GOLDEN_STEP,
        "id_burst_frames": capture.ID_BURST_FRAMES,
        "id_burst_step": capture.ID_BURST_STEP,
        "pose_exposure_s": capture.POSE_EXPOSURE_S,
        "id_exposure_s": capture.ID_EXPOSURE_S,
        "id_max_exposure_s": capture.longest_id_exposure_s(),
        "id_brightness_fraction": capture.ID_BRIGHTNESS_FRACTION,
        "window_per_panel": crop.WINDOW_PER_PANEL,
        "window_block_divisor": crop.BLOCK_DIVISOR,
        "window_min_contrast_dn": crop.MIN_CONTRAST_DN,
        "window_edge_blocks": crop.EDGE_BLOCKS,
        "window_edge_px": crop.EDGE_PX,
        "levels_coarse_short_side_px": windows.COARSE_SHORT_SIDE_PX,
        "levels_plateau_fraction": windows.PLATEAU_FRACTION,
    }


def rendered_protocol() -> str:
    return json.dumps(capture_protocol(), indent=2) + "\n"


def main() -> None:
    PROTOCOL_PATH.write_text(rendered_protocol())
    print(f"wrote {PROTOCOL_PATH}")


if __name__ == "__main__":
    main()
