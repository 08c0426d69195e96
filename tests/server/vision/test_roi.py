"""Coarse ROI stage: where the coarse view ends must not decide whether a panel is cut off."""

import numpy as np

from server.vision.binarize import Levels
from server.vision.roi import RoiRules, _grey_level_counts, coarse_levels, coarse_view, find_roi
from shared_schemas import FailureReason
from shared_schemas.windows import grey_level_counts, view_levels

HEIGHT, WIDTH = 1296, 970  # step 2: the frame's last row and column are not on the grid


def panel_frame(x0: int, x1: int, y0: int = 500, y1: int = 700) -> np.ndarray:
    pixels = np.full((HEIGHT, WIDTH), 8, np.uint8)
    pixels[y0:y1, x0:x1] = 255
    return pixels


def test_coarse_view_keeps_the_last_row_and_column():
    pixels = np.arange(HEIGHT * WIDTH, dtype=np.int64).reshape(HEIGHT, WIDTH)
    small = coarse_view(pixels, 2)
    assert small.shape == (649, 486)
    assert small[-1, -1] == pixels[-1, -1] and small[0, -1] == pixels[0, -1] and small[-1, 0] == pixels[-1, 0]
    np.testing.assert_array_equal(small[:-1, :-1], pixels[::2, ::2])


def test_panel_one_pixel_inside_the_far_border_is_not_cut_off():
    # the panel's last column is the coarse grid's last column, one pixel short of the border
    roi = find_roi(panel_frame(WIDTH - 202, WIDTH - 1))
    assert not hasattr(roi, "reason"), roi
    assert roi.x1 == WIDTH
    roi = find_roi(panel_frame(400, 600, HEIGHT - 202, HEIGHT - 1))
    assert not hasattr(roi, "reason"), roi


def test_panel_on_the_far_border_gives_a_region_that_reaches_the_border():
    # the fine stage flags it cut and fits its visible outline (server.pose.outline)
    roi = find_roi(panel_frame(WIDTH - 150, WIDTH))
    assert not hasattr(roi, "reason"), roi
    assert roi.x1 == WIDTH
    roi = find_roi(panel_frame(400, 600, HEIGHT - 150, HEIGHT))
    assert not hasattr(roi, "reason"), roi
    assert roi.y1 == HEIGHT


def test_a_window_is_read_on_the_full_frames_grid_and_finds_the_same_region():
    from server.vision.binarize import Levels
    from server.vision.roi import FrameView

    pixels = panel_frame(300, 520, 611, 800)
    whole = find_roi(pixels)
    x, y = 271, 581  # a tight window (the panel is 62 % of it) that starts off the full frame's grid (step 2)
    window = pixels[y : y + 250, x : x + 270]
    view = FrameView(full_size=(WIDTH, HEIGHT), offset=(x, y), levels=whole.levels)
    assert view.grid(window.shape, RoiRules()) == (2, (1, 1))
    found = find_roi(window, view=view)
    assert (found.x0 + x, found.y0 + y, found.x1 + x, found.y1 + y) == (whole.x0, whole.y0, whole.x1, whole.y1)
    # read on its own grid and with its own levels (mostly panel: the median is not the background)
    assert whole.levels == Levels(8.0, 255.0)
    alone = find_roi(window)
    assert getattr(alone, "reason", None) is FailureReason.no_beacon


def test_opencv_counts_the_grey_levels_as_numpy_does():
    # the coarse levels count with cv2.calcHist (float32), the contract's rule with np.bincount
    rng = np.random.default_rng(3)
    view = coarse_view(rng.integers(0, 256, (HEIGHT, WIDTH), dtype=np.uint8), 2)[::2]  # rows of a view, not contiguous
    np.testing.assert_array_equal(_grey_level_counts(view), grey_level_counts(view))
    assert coarse_levels(view) == Levels(*view_levels(view))
