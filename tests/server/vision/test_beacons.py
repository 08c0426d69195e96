import cv2
import numpy as np

from server.vision.beacons import CandidateRules, blob_mask, find_beacon_blobs


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
    y0, x0, mask = blob_mask(image, found.blobs[0], found)
    assert abs(int(mask.sum()) - 120 * 120) < 600


def test_bad_input_is_named():
    import pytest

    with pytest.raises(ValueError, match="pixels"):
        find_beacon_blobs(np.zeros((10, 10, 3), np.uint8))


# 300 x 401 with a 50 px coarse view: step 6, and neither height - 1 nor width - 1 is a multiple
# of it, so the grid's last column is 396 and its last row 294, short of the frame's 400 and 299.
SMALL_VIEW = CandidateRules(coarse_short_side_px=50)


def square_frame(x0: int, x1: int, y0: int, y1: int) -> np.ndarray:
    image = np.full((300, 401), 8, np.uint8)
    image[y0:y1, x0:x1] = 250
    return image


def test_a_panel_a_few_pixels_inside_the_far_border_is_not_cut_off():
    # right edge at column 397 (3 px inside) covers the grid's last column, not the frame's
    found = find_beacon_blobs(square_frame(298, 398, 100, 200), SMALL_VIEW)
    assert found.step == 6 and len(found.blobs) == 1
    blob = found.blobs[0]
    assert not blob.cut_off
    x, y, w, h = blob.bounding_box
    assert abs(x - 298) <= 6 and abs(x + w - 398) <= 6 and x + w <= 401
    assert abs(y - 100) <= 6 and abs(y + h - 200) <= 6
    assert abs(blob.centroid_px[0] - 347.5) <= 3 and abs(blob.centroid_px[1] - 149.5) <= 3
    assert blob.contour_px[:, 0].max() <= 397 and blob.contour_px[:, 0].min() >= 298
    # bottom edge at row 297 (2 px inside the last row, 299)
    found = find_beacon_blobs(square_frame(150, 250, 197, 298), SMALL_VIEW)
    assert len(found.blobs) == 1 and not found.blobs[0].cut_off
    x, y, w, h = found.blobs[0].bounding_box
    assert abs(y + h - 298) <= 6 and y + h <= 300


def test_a_panel_on_the_far_border_is_cut_off_and_stays_in_the_frame():
    found = find_beacon_blobs(square_frame(301, 401, 100, 200), SMALL_VIEW)
    assert len(found.blobs) == 1 and found.blobs[0].cut_off
    x, y, w, h = found.blobs[0].bounding_box
    assert x + w == 401  # the box ends at the frame's border, not beyond it
    assert found.blobs[0].contour_px[:, 0].max() == 400  # the frame's last column
    found = find_beacon_blobs(square_frame(150, 250, 200, 300), SMALL_VIEW)
    assert len(found.blobs) == 1 and found.blobs[0].cut_off
    x, y, w, h = found.blobs[0].bounding_box
    assert y + h == 300 and found.blobs[0].contour_px[:, 1].max() == 299


def shapes_frame() -> np.ndarray:
    image = np.full((600, 800), 10, np.uint8)
    image[100:200, 100:200] = 250  # a square panel
    cv2.circle(image, (650, 150), 50, 250, -1)  # a round downlight
    image[350:390, 100:260] = 250  # a 4 : 1 strip (a 1200 x 300 mm panel)
    return image


def test_blobs_are_judged_by_the_looks_of_the_map_s_panels():
    from server.vision.beacons import panel_looks
    from shared_schemas import Beacon

    square = Beacon(id=1, center_m=[0, 0, 2], side_m=0.6)
    circle = Beacon(id=2, center_m=[1, 0, 2], shape="circle", diameter_m=0.2)
    strip = Beacon(id=3, center_m=[2, 0, 2], width_m=1.2, height_m=0.3)

    def found_centres(rules):
        found = find_beacon_blobs(shapes_frame(), rules)
        return sorted((round(b.centroid_px[0] / 50) * 50, round(b.centroid_px[1] / 50) * 50) for b in found.blobs)

    # no looks: the paper's square only (the default, as before)
    assert found_centres(CandidateRules()) == [(150, 150)]
    assert found_centres(CandidateRules().for_beacons([square])) == [(150, 150)]
    # a map of downlights: the square fills too much of its box to be one, the strip is too long
    found = find_beacon_blobs(shapes_frame(), CandidateRules().for_beacons([circle]))
    assert [round(b.centroid_px[0]) for b in found.blobs] == [650]
    # a map with all three shapes: a blob is a candidate if it looks like any of them
    rules = CandidateRules().for_beacons([square, circle, strip, square.model_copy(update={"id": 4})])
    assert len(rules.looks) == 3  # one look per distinct shape
    assert found_centres(rules) == [(150, 150), (200, 350), (650, 150)]
    # looks already set are kept; what is rejected says it looks like none of them
    assert rules.for_beacons([square]) is rules
    image = shapes_frame()
    image[450:560, 500:740] = 250  # 2.2 : 1, like none of them
    found = find_beacon_blobs(image, CandidateRules(looks=panel_looks([square, circle])))
    assert any("none of the map's 2 panels" in r for r in found.rejected)


def test_components_give_opencvs_labels_stats_and_centroids():
    from server.vision.beacons import _centroid, _components

    rng = np.random.default_rng(3)
    for trial in range(60):
        height, width = (int(v) for v in rng.integers(5, 200, 2))
        mask = np.zeros((height, width), np.uint8)
        for _ in range(int(rng.integers(0, 6))):
            centre = (int(rng.integers(0, width)), int(rng.integers(0, height)))
            cv2.circle(mask, centre, int(rng.integers(1, 40)), 255, -1)
        if trial % 3 == 0:
            mask[rng.random(mask.shape) < 0.002] = 255  # specks: beyond a few components, OpenCV's own stats
        mask[:: 5 + trial % 4] = 0
        count, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
        own_count, own_labels, own_stats = _components(mask)
        assert own_count == count and np.array_equal(own_labels, labels)
        assert np.array_equal(own_stats[1:], stats[1:])
        for label in range(1, count):
            assert np.array_equal(_centroid(labels, label, int(stats[label, cv2.CC_STAT_AREA])), centroids[label])


def test_a_vertical_closing_by_running_extremes_is_opencvs():
    from server.vision.beacons import _closed, _closed_columns

    rng = np.random.default_rng(5)
    for trial in range(400):
        height, width, half = int(rng.integers(1, 80)), int(rng.integers(1, 12)), int(rng.integers(1, 40))
        mask = np.where(rng.random((height, width)) < rng.uniform(0.01, 0.9), 255, 0).astype(np.uint8)
        expected = _closed(mask, np.ones((2 * half + 1, 1), np.uint8))
        assert np.array_equal(_closed_columns(mask, half), expected), trial
