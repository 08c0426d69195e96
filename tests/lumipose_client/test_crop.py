"""A frame cut to its beacon's window gives the same fix as the whole frame."""

import numpy as np
import pytest
from pydantic import ValidationError

from lumipose_client.crop import beacon_window, crop_frame
from server.camera import resolve_camera
from server.ingest import decode_frame, read_fixture
from server.locator import locate
from shared_schemas import FrameMeta, load_map
from tests.conftest import FIXTURE


def test_cropped_frame_gives_the_same_fix_and_is_much_smaller():
    frame = read_fixture(FIXTURE)
    meta, data = crop_frame(frame.pixels, frame.meta)
    assert meta.crop is not None and len(data) < frame.pixels.size / 2
    whole, cropped = locate(frame, load_map()), locate(decode_frame(data, meta), load_map())
    assert whole.ok and cropped.ok
    np.testing.assert_allclose(cropped.position_m, whole.position_m, atol=1e-6)
    np.testing.assert_allclose(np.array(cropped.corners_px) + [meta.crop.x, meta.crop.y], whole.corners_px, atol=1e-3)


def test_the_window_holds_the_brightest_panel_with_background_around_it():
    pixels = np.full((600, 800), 10, np.uint8)
    pixels[100:160, 500:560] = 255  # the panel
    pixels[400:430, 100:130] = 200  # a dimmer lamp, also above the half-way level
    x0, y0, x1, y1 = beacon_window(pixels)
    # the server's region of interest (12 px around the panel here) and the lamp stays out
    assert x0 <= 500 - 12 and y0 <= 100 - 12 and x1 >= 560 + 12 and y1 >= 160 + 12
    assert x0 > 130 and y1 < 400 and x1 - x0 < 2 * 60


def test_a_panel_in_the_rows_and_columns_the_coarse_view_leaves_out_is_kept_whole():
    pixels = np.full((601, 803), 10, np.uint8)  # blocks of 2 px: the last row and column are not in the view
    pixels[560:, 760:] = 255
    assert beacon_window(pixels)[2:] == (803, 601)


def test_a_frame_without_a_bright_region_is_sent_whole():
    meta = FrameMeta(width=80, height=60, camera={"profile": "xiaomi-mi8-front"})
    pixels = np.full((60, 80), 30, np.uint8)
    pixels[::7, ::5] = 45  # texture, but nothing stands 20 DN above the background
    assert crop_frame(pixels, meta) == (meta, pixels.tobytes())


def test_profile_camera_of_a_crop_is_the_full_frames_shifted():
    full = FrameMeta(width=3024, height=4032, camera={"profile": "xiaomi-mi8-rear"})
    crop = FrameMeta(width=400, height=300, camera={"profile": "xiaomi-mi8-rear"},
                     crop={"x": 1000, "y": 2000, "full_width": 3024, "full_height": 4032})
    whole, window = resolve_camera(full), resolve_camera(crop)
    assert window.fx == whole.fx and (window.cx, window.cy) == (whole.cx - 1000, whole.cy - 2000)


def test_crop_must_fit_in_its_full_frame():
    with pytest.raises(ValidationError, match="does not fit"):
        FrameMeta(width=400, height=300, camera={"profile": "xiaomi-mi8-rear"},
                  crop={"x": 2800, "y": 0, "full_width": 3024, "full_height": 4032})
