"""Blur and threshold stages: the level follows the frame, the blur leaves an edge in place."""

import numpy as np

from server.vision.binarize import Levels, blur, estimate_levels, threshold


def test_levels_follow_background_and_plateau():
    rng = np.random.default_rng(0)
    image = np.clip(rng.normal(30, 2, (400, 300)), 0, 255).astype(np.uint8)
    image[100:130, 100:140] = 255  # a panel covering 1 % of the frame
    levels = estimate_levels(image)
    assert 28 <= levels.background <= 32 and levels.plateau == 255
    assert levels.threshold == (levels.background + levels.plateau) / 2


def test_box_blur_keeps_a_straight_edge_where_it_is():
    # a ramp edge whose mid level lies at x = 50.3: the blurred mask must switch at the same column
    x = np.arange(100, dtype=float)
    row = np.clip(8 + (x - 50.3 + 2) / 4 * 247, 8, 255)[::-1]  # bright on the left
    image = np.tile(row, (40, 1)).round().astype(np.uint8)
    levels = Levels(background=8, plateau=255)
    for kernel in (3, 5):
        plain = threshold(image, levels)[20]
        blurred = threshold(blur(image, kernel), levels)[20]
        np.testing.assert_array_equal(plain, blurred)
