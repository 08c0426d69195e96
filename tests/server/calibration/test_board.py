"""Finding the board: corners against the rendered truth, colour, no board, a spec that does not match."""

import cv2
import numpy as np
import pytest

from server.calibration.board import BoardRules, _saddle_points, charuco_board, corner_points_m, find_board
from shared_schemas.calibration import BoardSpec
from simulator.board import PoseSet
from tests.calibration_photos import BOARD, HEIGHT, LENS, WIDTH, photo_set


def _errors_px(view, pose) -> np.ndarray:
    truth = LENS.project(corner_points_m(BOARD, view.corner_ids) @ pose.rotation.T + pose.translation)
    return np.linalg.norm(np.asarray(view.corners_px) - truth, axis=1)


def test_corners_match_the_rendered_truth_to_a_tenth_of_a_pixel():
    photos, poses = photo_set(PoseSet.good)
    errors = []
    for photo, pose in zip(photos[:8], poses[:8], strict=True):
        view = find_board(photo, BOARD, "p")
        if view is not None:  # a far, tilted board's markers may be unreadable at 640 x 480
            assert (view.width, view.height) == (WIDTH, HEIGHT)
            errors.append(_errors_px(view, pose))
    assert len(errors) >= 6
    errors = np.concatenate(errors)
    assert np.median(errors) < 0.05 and np.percentile(errors, 95) < 0.15, (np.median(errors), errors.max())


def test_a_colour_photo_gives_the_grey_photos_corners():
    photo = photo_set(PoseSet.good)[0][1]
    grey, colour = find_board(photo, BOARD, "g"), find_board(cv2.cvtColor(photo, cv2.COLOR_GRAY2BGR), BOARD, "c")
    assert grey is not None and colour is not None
    assert grey.corner_ids == colour.corner_ids and np.allclose(grey.corners_px, colour.corners_px)


def test_no_board_is_none():
    rng = np.random.default_rng(0)
    assert find_board(rng.integers(0, 255, (HEIGHT, WIDTH), dtype=np.uint8), BOARD, "noise") is None
    assert find_board(np.full((HEIGHT, WIDTH), 90, np.uint8), BOARD, "grey") is None


@pytest.mark.parametrize("change", [{"dictionary": "DICT_5X5_100"}, {"squares_x": 6}, {"squares_x": 9, "squares_y": 4}])
def test_a_spec_that_does_not_match_the_photo_finds_nothing(change):
    other = BoardSpec.model_validate({**BOARD.model_dump(), **change})
    photos, _ = photo_set(PoseSet.good)
    assert all(find_board(photo, other, "p") is None for photo in photos[:6])


def test_corner_ids_follow_opencvs_board():
    ids = np.arange(BOARD.inner_corners)
    assert np.allclose(corner_points_m(BOARD, ids), charuco_board(BOARD).getChessboardCorners())
    assert np.allclose(corner_points_m(BOARD, [0, 7])[:, :2], [[0.04, 0.04], [0.08, 0.08]])
    with pytest.raises(ValueError, match="not on a 7 x 5 board"):
        corner_points_m(BOARD, [BOARD.inner_corners])


def test_bad_images_are_named():
    with pytest.raises(ValueError, match="8-bit"):
        find_board(np.zeros((10, 10), np.float32), BOARD, "f")
    with pytest.raises(ValueError, match="grey"):
        find_board(np.zeros((10, 10, 2), np.uint8), BOARD, "two channels")


@pytest.mark.parametrize("x", [80.0, 4100.0])
def test_the_saddle_fit_converges_far_from_the_origin(x):
    # getRectSubPix takes the window's centre in float32, 4.9e-4 px apart beyond 4096: a convergence tolerance
    # below that never converged there (most corners of a full-size photo's lower half were lost)
    rng = np.random.default_rng(1)
    height, width = 161, int(x) + 200
    ys, xs = np.mgrid[0:height, 0:width].astype(float)
    for _ in range(5):
        corner = np.array([x, 80.0]) + rng.uniform(-0.5, 0.5, 2)
        u = (xs - corner[0]) * np.cos(0.3) + (ys - corner[1]) * np.sin(0.3)
        v = -(xs - corner[0]) * np.sin(0.3) + (ys - corner[1]) * np.cos(0.3)
        sharp = cv2.GaussianBlur(np.where(u * v > 0, 200.0, 30.0), (0, 0), 1.0)
        photo = np.clip(sharp + rng.normal(0, 2, sharp.shape), 0, 255).astype(np.uint8)
        # a board held close: the largest window (BoardRules.max_window_px 20) and its blur
        smooth = cv2.GaussianBlur(photo.astype(np.float32), (0, 0), 13.0)
        refined, converged = _saddle_points(smooth, np.array([corner + [1.0, -0.7]]), 18, BoardRules())
        assert converged[0] and np.linalg.norm(refined[0] - corner) < 0.05
