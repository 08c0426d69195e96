"""`lumipose render OUT --png`: the fixture and a PNG of the same pixels, which locate reads too."""

import cv2
import numpy as np

from lumipose_cli.main import main
from shared_schemas import FrameMeta


def test_render_png_holds_the_frames_own_pixels(tmp_path, capsys):
    stem = tmp_path / "frame"
    assert main(["render", str(stem), "--position", "0.05", "0", "0", "--scale", "0.1", "--png"]) == 0
    assert f"wrote {stem}.png" in capsys.readouterr().out
    meta = FrameMeta.model_validate_json(stem.with_suffix(".json").read_text())
    plane = np.frombuffer(stem.with_suffix(".y").read_bytes(), np.uint8).reshape(meta.height, meta.stride)
    picture = cv2.imread(str(stem.with_suffix(".png")), cv2.IMREAD_UNCHANGED)
    assert picture.ndim == 2 and np.array_equal(picture, plane[:, : meta.width])
    assert picture.max() > 200  # the panel is in it
    assert main(["render", str(tmp_path / "plain"), "--scale", "0.1"]) == 0
    assert not (tmp_path / "plain.png").exists()
