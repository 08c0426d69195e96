"""The board renderer and its pose sets: the image lands where the lens puts the board, the sets
are what their names say."""

import cv2
import numpy as np

from server.calibration.board import corner_points_m
from simulator.board import BoardLook, BoardPose, PoseSet, board_poses, corners_in_frame, render_board
from simulator.render import SensorModel
from tests.calibration_photos import BOARD, HEIGHT, LENS, RULES, WIDTH


def test_the_rendered_squares_sit_where_the_lens_projects_them():
    # noiseless and unblurred: each pixel is the mean of its 4 x 4 samples of the board's texture
    look = BoardLook(sensor=SensorModel(background_dn=0.0, psf_sigma_px=0.0, read_noise_dn=0.0,
                                        electrons_per_dn=1e12))
    centre = np.array([BOARD.squares_x, BOARD.squares_y, 0]) * BOARD.square_m / 2
    tilted = cv2.Rodrigues(np.array([0.4, -0.3, 0.2]))[0]
    pose = BoardPose(rotation=tilted, translation=np.array([0.0, 0.0, 0.4]) - tilted @ centre)
    image = render_board(BOARD, LENS, pose, WIDTH, HEIGHT, np.random.default_rng(0), look).astype(float)
    white, black = look.light_dn * look.white, look.light_dn * look.black
    squares = np.array([[i + 0.5, j + 0.5, 0.0] for j in range(BOARD.squares_y) for i in range(BOARD.squares_x)])
    pixels = np.rint(LENS.project(squares * BOARD.square_m @ tilted.T + pose.translation)).astype(int)
    # OpenCV's layout: the top-left square black, alternating; the white squares' centres hold a marker's
    # centre cell, black or white, so only the black squares are checked for black, and the paper around
    for (x, y), (i, j) in zip(pixels, squares[:, :2].astype(int), strict=True):
        if (i + j) % 2 == 0:
            assert abs(image[y, x] - black) < 1, (i, j, image[y, x])
    margin = LENS.project((np.array([[-0.25, -0.25, 0.0]]) * BOARD.square_m) @ tilted.T + pose.translation)
    x, y = np.rint(margin[0]).astype(int)
    assert abs(image[y, x] - white) < 1
    # a corner's pixel straddles two black and two white squares: its level is between
    corner = np.rint(LENS.project(corner_points_m(BOARD, [8]) @ tilted.T + pose.translation)[0]).astype(int)
    assert black + 20 < image[corner[1], corner[0]] < white - 20


def test_the_good_set_has_realistic_poses_covering_every_corner_of_the_image():
    rng = np.random.default_rng(5)
    poses = board_poses(BOARD, LENS, WIDTH, HEIGHT, 12, rng, PoseSet.good, RULES)
    tilts = [pose.tilt_deg for pose in poses]
    centre = np.array([BOARD.squares_x, BOARD.squares_y, 0]) * BOARD.square_m / 2
    distances = [np.linalg.norm(pose.rotation @ centre + pose.translation) for pose in poses]
    assert all(10 <= t <= 50 for t in tilts) and all(0.3 <= d <= 0.55 + 1e-9 for d in distances)
    assert all(corners_in_frame(BOARD, LENS, pose, WIDTH, HEIGHT) >= RULES.min_corners_in_frame for pose in poses)
    corners = np.concatenate([LENS.project(corner_points_m(BOARD, np.arange(BOARD.inner_corners))
                                           @ pose.rotation.T + pose.translation) for pose in poses])
    inside = corners[(corners[:, 0] >= 0) & (corners[:, 0] < WIDTH) & (corners[:, 1] >= 0) & (corners[:, 1] < HEIGHT)]
    for frame_corner in ([0, 0], [WIDTH, 0], [0, HEIGHT], [WIDTH, HEIGHT]):
        assert np.linalg.norm(inside - frame_corner, axis=1).min() < RULES.corner_reach * WIDTH


def test_the_poor_sets_are_frontal_or_in_one_corner():
    rng = np.random.default_rng(6)
    frontal = board_poses(BOARD, LENS, WIDTH, HEIGHT, 8, rng, PoseSet.frontal, RULES)
    assert max(pose.tilt_deg for pose in frontal) < RULES.frontal_tilt_deg
    corner = board_poses(BOARD, LENS, WIDTH, HEIGHT, 8, rng, PoseSet.corner, RULES)
    for pose in corner:
        points = LENS.project(corner_points_m(BOARD, np.arange(BOARD.inner_corners)) @ pose.rotation.T
                              + pose.translation)
        assert np.median(points[:, 0]) < WIDTH / 2 and np.median(points[:, 1]) < HEIGHT / 2
