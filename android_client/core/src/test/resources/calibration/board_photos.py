"""Board photos for CalibrationEndToEndTest: a ChArUco board (the BoardSpec given as JSON) seen by a
known pinhole from several tilted poses, rendered by OpenCV (the board image warped by the plane's
homography, blurred by half a pixel) as packed Y8 files NAME.y, and a blank photo with no board.
Writes truth.json ({fx, fy, cx, cy, width, height, photos: [names]}) into the directory given.

usage: board_photos.py OUT_DIR BOARD_JSON
"""

import json
import sys
from pathlib import Path

import cv2
import numpy as np

out = Path(sys.argv[1])
spec = json.loads(sys.argv[2])
WIDTH, HEIGHT = 640, 480
FX, FY, CX, CY = 600.0, 598.0, 322.0, 236.5
K = np.array([[FX, 0, CX], [0, FY, CY], [0, 0, 1]])
PX_PER_SQUARE = 80  # the board image: finer than the photos, so warping does not alias

dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, spec.get("dictionary", "DICT_5X5_100")))
board = cv2.aruco.CharucoBoard((spec["squares_x"], spec["squares_y"]), spec["square_m"], spec["marker_m"], dictionary)
art = board.generateImage((spec["squares_x"] * PX_PER_SQUARE, spec["squares_y"] * PX_PER_SQUARE))
m_per_px = spec["square_m"] / PX_PER_SQUARE
# board image pixel centre (u, v) lies at ((u + 1/2) s, (v + 1/2) s) on the board, metres from its top-left corner
to_board = np.array([[m_per_px, 0, 0.5 * m_per_px], [0, m_per_px, 0.5 * m_per_px], [0, 0, 1]])
centre = np.array([spec["squares_x"], spec["squares_y"]]) * spec["square_m"] / 2

names = []
rng = np.random.default_rng(7)
tilts = [
    (0, 0),
    (25, 0),
    (-25, 0),
    (0, 25),
    (0, -25),
    (20, 20),
    (-20, 20),
    (20, -20),
    (-20, -20),
    (30, 10),
    (-10, 30),
    (15, -30),
]
for i, (ax, ay) in enumerate(tilts):
    rvec = np.radians([ax, ay, rng.uniform(-20, 20)])
    rot, _ = cv2.Rodrigues(rvec)
    distance = rng.uniform(0.28, 0.36)
    # the board's centre on a spread of image points, so the corners cover the frame
    aim = np.array([rng.uniform(-0.25, 0.25) * WIDTH / FX, rng.uniform(-0.25, 0.25) * HEIGHT / FY, 1.0])
    t = aim * distance - rot @ np.array([centre[0], centre[1], 0.0])
    h = K @ np.column_stack([rot[:, 0], rot[:, 1], t]) @ to_board
    photo = cv2.warpPerspective(art, h, (WIDTH, HEIGHT), flags=cv2.INTER_AREA, borderValue=128)
    photo = cv2.GaussianBlur(photo, (0, 0), 0.5)
    name = f"board_{i:02d}"
    (out / f"{name}.y").write_bytes(np.ascontiguousarray(photo, np.uint8).tobytes())
    names.append(name)
(out / "blank.y").write_bytes(np.full((HEIGHT, WIDTH), 128, np.uint8).tobytes())
(out / "truth.json").write_text(
    json.dumps({"fx": FX, "fy": FY, "cx": CX, "cy": CY, "width": WIDTH, "height": HEIGHT, "photos": names})
)
