"""The contract's window rule: levels a client can reproduce exactly, on the full frame's grid."""

import numpy as np

from shared_schemas.windows import coarse_step, coarse_view, frame_levels, histogram_levels


def test_levels_are_the_median_and_the_top_quantile_by_whole_counts():
    samples = np.array([10] * 5 + [11] * 5 + [255] * 2, np.uint8)  # 12 samples: 6 reach half at level 11
    assert histogram_levels(samples) == (11.0, 255.0)
    assert histogram_levels(np.array([10] * 6 + [12] * 6, np.uint8)) == (10.0, 12.0)  # exactly half: the lower


def test_frame_levels_read_every_other_row_of_the_coarse_view():
    pixels = np.full((960, 1300), 30, np.uint8)  # step 2
    pixels[2::4] = 200  # rows 2, 6, ...: view rows 1, 3, ... which the levels skip
    assert coarse_step(*pixels.shape) == 2 and frame_levels(pixels) == (30.0, 30.0)
    pixels[::4] = 200  # view rows 0, 2, ...
    assert frame_levels(pixels) == (200.0, 200.0)


def test_the_coarse_view_starts_where_the_full_frames_grid_does():
    pixels = np.arange(20 * 30).reshape(20, 30)
    window = pixels[5:17, 7:22]  # offset (7, 5) on a grid of step 4: first grid pixel at (8, 8)
    small = coarse_view(window, 4, (1, 3))
    np.testing.assert_array_equal(small[:, :-1], pixels[8:17:4, 8:22:4])  # and the window's last column
    np.testing.assert_array_equal(small[:, -1], window[3::4, -1])
