"""Rendered ChArUco photos shared by the calibration tests (not tests themselves): small, cached.

640 x 480 through a lens with a phone-like distortion, a 7 x 5 board of 40 mm squares held
0.3-0.55 m away (at this size a farther board's markers are too small to read).
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from server.calibration.board import find_board
from server.calibration.lens import Lens
from shared_schemas.calibration import BoardSpec, BoardView
from simulator.board import BoardPose, PoseRules, PoseSet, board_poses, render_board

WIDTH, HEIGHT = 640, 480
LENS = Lens(560.0, 557.0, 326.0, 233.0, (0.06, -0.03, 5e-4, -4e-4, 0.0))
BOARD = BoardSpec(squares_x=7, squares_y=5, square_m=0.04, marker_m=0.028, dictionary="DICT_4X4_50")
RULES = PoseRules(distance_m=(0.3, 0.55))
VIEWS = 12


@functools.cache
def photo_set(kind: PoseSet = PoseSet.good, seed: int = 3) -> tuple[tuple[np.ndarray, ...], tuple[BoardPose, ...]]:
    """VIEWS grey photos of the set and their true poses."""
    rng = np.random.default_rng(seed)
    poses = board_poses(BOARD, LENS, WIDTH, HEIGHT, VIEWS, rng, kind, RULES)
    photos = tuple(render_board(BOARD, LENS, pose, WIDTH, HEIGHT, rng) for pose in poses)
    for photo in photos:
        photo.flags.writeable = False
    return photos, tuple(poses)


@functools.cache
def view_set(kind: PoseSet = PoseSet.good) -> tuple[BoardView, ...]:
    """The boards found on `photo_set(kind)`."""
    photos, _ = photo_set(kind)
    found = (find_board(photo, BOARD, f"{kind.value}-{k:02d}") for k, photo in enumerate(photos))
    return tuple(view for view in found if view is not None)


def encoded(photo: np.ndarray, extension: str = ".png", colour: bool = False) -> bytes:
    """The photo as PNG or JPEG bytes, grey or colour (BGR)."""
    image = cv2.cvtColor(photo, cv2.COLOR_GRAY2BGR) if colour else photo
    params = [cv2.IMWRITE_JPEG_QUALITY, 97] if extension == ".jpg" else []
    ok, data = cv2.imencode(extension, image, params)
    assert ok
    return data.tobytes()
