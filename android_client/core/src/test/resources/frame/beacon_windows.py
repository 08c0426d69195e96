"""Frames, crop.py's windows and windows.py's levels for BeaconWindowTest and FrameLevelsTest:
writes NAME.y (packed Y8) and windows.json ({name: {width, height, window: [x0, y0, x1, y1] or
null, levels: [background, plateau]}}) into the directory given."""

import json
import sys
from pathlib import Path

import numpy as np

from lumipose_client.crop import beacon_window
from server.ingest import read_fixture
from shared_schemas.windows import frame_levels
from simulator.bench_service import service_frame
from tests.conftest import FIXTURE

out = Path(sys.argv[1])
frames = {"bench_1m": read_fixture(FIXTURE).pixels}
for width, distance_m in ((1080, 1.0), (1080, 2.0), (1080, 3.0), (None, 1.0), (None, 3.0)):
    meta, data, _ = service_frame(width, distance_m)
    frames[f"rendered_{width or 'full'}_{distance_m:g}m"] = np.frombuffer(data, np.uint8).reshape(meta.height, meta.width)

lamp = np.full((600, 800), 10, np.uint8)
lamp[100:160, 500:560] = 255  # the panel
lamp[400:430, 100:130] = 200  # a dimmer lamp, also above the half-way level
frames["panel_and_lamp"] = lamp
corner = np.full((601, 803), 10, np.uint8)  # blocks of 2 px: the last row and column are not in the view
corner[560:, 760:] = 255
frames["panel_in_the_left_out_corner"] = corner
top_left = np.full((480, 640), 12, np.uint8)
top_left[0:40, 0:50] = 240
frames["panel_at_the_top_left"] = top_left
flat = np.full((60, 80), 30, np.uint8)
flat[::7, ::5] = 45  # texture, but nothing stands 20 DN above the background
frames["no_panel"] = flat
rng = np.random.default_rng(7)
noisy = rng.integers(0, 40, (1000, 1500), dtype=np.uint8)
noisy[300:420, 700:800] = 180 + rng.integers(0, 60, (120, 100), dtype=np.uint8)
frames["noisy_panel"] = noisy
frames["odd_sizes"] = rng.integers(0, 256, (963, 1441), dtype=np.uint8)  # the view's extra last row and column

windows = {}
for name, pixels in frames.items():
    (out / f"{name}.y").write_bytes(np.ascontiguousarray(pixels).tobytes())
    window = beacon_window(pixels)
    windows[name] = {"width": pixels.shape[1], "height": pixels.shape[0],
                     "window": None if window is None else [int(v) for v in window],
                     "levels": [float(v) for v in frame_levels(pixels)]}
(out / "windows.json").write_text(json.dumps(windows))
