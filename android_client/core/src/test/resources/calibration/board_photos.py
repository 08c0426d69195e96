"""Board photos for CalibrationEndToEndTest: a ChArUco board (the BoardSpec given as JSON) seen by a
known pinhole from several tilted poses, rendered by OpenCV (the board image warped by the plane's
homography at 4 x 4 samples a pixel, then averaged) as packed Y8 files NAME.y, and a blank photo with no board.
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
PX_PER_SQUARE = 200  # the board image: finer than the supersampled photos
SUPERSAMPLE = 4  # rendered at 4 x 4 samples a pixel, then averaged: edges as a lens and sensor make them

dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, spec.get("dictionary", "DICT_5X5_100")))
board = cv2.aruco.CharucoBoard((spec["squares_x"], spec["squares_y"]), spec["square_m"], spec["marker_m"], dictionary)
art = board.generateImage((spec["squares_x"] * PX_PER_SQUARE, spec["squares_y"] * PX_PER_SQUARE))
m_per_px = spec["square_m"] / PX_PER_SQUARE
# board image pixel centre (u, v) lies at ((u + 1/2) s, (v + 1/2) s) on the board, metres from its top-left corner
to_board = np.array([[m_per_px, 0, 0.5 * m_per_px], [0, m_per_px, 0.5 * m_per_px], [0, 0, 1]])
centre = np.array([spec["squares_x"], spec["squares_y"]]) * spec["square_m"] / 2

names = []
rng = np.random.default_rng(7)
# the board's centre aimed at the image's corners and edges, each four times with other tilts, so
# that the corners cover every cell of the server's grid and the normals vary (Zhang's method)
aims = [(-0.3, -0.3), (0.3, -0.3), (-0.3, 0.3), (0.3, 0.3), (0.0, -0.3), (0.0, 0.3), (-0.3, 0.0), (0.3, 0.0)]
tilts = [(25, 0), (-25, 0), (0, 25), (0, -25), (20, 20), (-20, 20), (20, -20), (-20, -20)]
for i in range(4 * len(aims)):
    ax, ay = tilts[(i * 3) % len(tilts)]
    u, v = aims[i % len(aims)]
    rvec = np.radians([ax, ay, rng.uniform(-20, 20)])
    rot, _ = cv2.Rodrigues(rvec)
    # far enough in the corners that the whole board stays in the frame, near enough elsewhere to fill it
    distance = rng.uniform(0.5, 0.56) if i % len(aims) < 4 else rng.uniform(0.3, 0.36)
    aim = np.array([u * WIDTH / FX, v * HEIGHT / FY, 1.0])
    t = aim * distance - rot @ np.array([centre[0], centre[1], 0.0])
    h = K @ np.column_stack([rot[:, 0], rot[:, 1], t]) @ to_board
    # a pixel centre x of the photo is x' = S (x + 1/2) - 1/2 of the supersampled image
    fine = np.array([[SUPERSAMPLE, 0, (SUPERSAMPLE - 1) / 2], [0, SUPERSAMPLE, (SUPERSAMPLE - 1) / 2], [0, 0, 1]])
    big = cv2.warpPerspective(
        art, fine @ h, (WIDTH * SUPERSAMPLE, HEIGHT * SUPERSAMPLE), flags=cv2.INTER_LINEAR, borderValue=128
    )
    photo = cv2.resize(big, (WIDTH, HEIGHT), interpolation=cv2.INTER_AREA)
    name = f"board_{i:02d}"
    (out / f"{name}.y").write_bytes(np.ascontiguousarray(photo, np.uint8).tobytes())
    names.append(name)
(out / "blank.y").write_bytes(np.full((HEIGHT, WIDTH), 128, np.uint8).tobytes())
(out / "truth.json").write_text(
    json.dumps({"fx": FX, "fy": FY, "cx": CX, "cy": CY, "width": WIDTH, "height": HEIGHT, "photos": names})
)
