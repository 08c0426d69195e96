"""Board photos for CalibrationEndToEndTest: the ChArUco board (the BoardSpec given as JSON) seen by a
known pinhole, posed and rendered by the simulator (`simulator.board`: a good set, the photos' blur,
noise and 8-bit clipping), written as packed Y8 files NAME.y, and a blank photo with no board.
Writes truth.json ({fx, fy, cx, cy, width, height, photos: [names]}) into the directory given.
With `mirrored`, every photo is flipped left-right as a front camera's preview writes it (the truth
stays the lens's: the server is to un-mirror the photos before fitting).

usage: board_photos.py OUT_DIR BOARD_JSON [VIEWS [mirrored]]
"""

import json
import sys
from pathlib import Path

import numpy as np

from server.calibration.lens import Lens
from shared_schemas.calibration import BoardSpec
from simulator.board import BoardLook, PoseRules, PoseSet, board_poses, render_board

WIDTH, HEIGHT = 640, 480
LENS = Lens(600.0, 598.0, 322.0, 236.5)
VIEWS = int(sys.argv[3]) if len(sys.argv) > 3 else 32
MIRRORED = len(sys.argv) > 4 and sys.argv[4] == "mirrored"
# 30 mm squares: nearer than the simulator's 0.3-0.8 m, or the markers are too small to read at 640 x 480
RULES = PoseRules(distance_m=(0.22, 0.42))

out = Path(sys.argv[1])
spec = BoardSpec.model_validate_json(sys.argv[2])
rng = np.random.default_rng(7)
names = []
for i, pose in enumerate(board_poses(spec, LENS, WIDTH, HEIGHT, VIEWS, rng, PoseSet.good, RULES)):
    name = f"board_{i:02d}"
    photo = render_board(spec, LENS, pose, WIDTH, HEIGHT, rng)
    (out / f"{name}.y").write_bytes((np.fliplr(photo) if MIRRORED else photo).tobytes())
    names.append(name)
blank = np.full((HEIGHT, WIDTH), round(BoardLook().background * BoardLook().light_dn), np.uint8)
(out / "blank.y").write_bytes(blank.tobytes())
truth = {"fx": LENS.fx, "fy": LENS.fy, "cx": LENS.cx, "cy": LENS.cy, "width": WIDTH, "height": HEIGHT}
(out / "truth.json").write_text(json.dumps({**truth, "photos": names}))
