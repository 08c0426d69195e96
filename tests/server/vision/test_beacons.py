import cv2
import numpy as np

from server.vision.beacons import blob_mask, find_beacon_blobs


def test_all_square_panels_are_found_a_round_lamp_is_not_and_a_cut_one_is_flagged():
    image = np.full((600, 800), 10, np.uint8)
    image[100:200, 100:200] = 250  # a panel
    image[300:380, 500:580] = 250  # a smaller panel
    cv2.circle(image, (650, 150), 50, 250, -1)  # a round lamp
    image[450:600, 50:150] = 250  # a panel cut by the bottom border
    found = find_beacon_blobs(image)
    assert [b.cut_off for b in found.blobs] == [True, False, False]  # largest first
    assert found.blobs[1].area_px > found.blobs[2].area_px
    assert any("79 %" in r for r in found.rejected)
    x, y, w, h = found.blobs[1].bounding_box
    assert abs(x - 100) <= 2 and abs(w - 100) <= 4


def test_striped_panels_stay_one_blob():
    image = np.full((400, 400), 5, np.uint8)
    panel = np.where((np.arange(120) // 10) % 2 == 0, 220, 70).astype(np.uint8)  # low level 0.3 of high
    image[100:220, 100:220] = panel[:, None]
    found = find_beacon_blobs(image)
    assert len(found.blobs) == 1
    y0, x0, mask = blob_mask(image, found.blobs[0], found.levels)
    assert abs(int(mask.sum()) - 120 * 120) < 600


def test_bad_input_is_named():
    import pytest

    with pytest.raises(ValueError, match="pixels"):
        find_beacon_blobs(np.zeros((10, 10, 3), np.uint8))
