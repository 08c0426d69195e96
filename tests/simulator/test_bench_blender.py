"""The optional Blender renderer against the exact projection (needs bpy)."""

import numpy as np
import pytest

from shared_schemas import Beacon, CameraIntrinsics
from simulator.bench_fidelity import edge_points, exact_corners_px
from simulator.render import CameraPose

bpy = pytest.importorskip("bpy", reason="bpy (Blender as a module) is an optional extra: pip install -e '.[blender]'")

from simulator.blender import render_blender  # noqa: E402

CAMERA = CameraIntrinsics(fx=977.78, fy=977.78, cx=239.5, cy=319.5)
SQUARE = Beacon(id=0, center_m=[0.0, 0.0, 1.0], side_m=0.174, corner_radius_m=0.0)


@pytest.mark.parametrize("offset_m", [0.0, 0.0013])
def test_blender_edges_lie_on_the_exact_projection(offset_m):
    pose = CameraPose(np.array([offset_m, 0.0, 0.0]), np.eye(3))
    crop = render_blender(SQUARE, CAMERA, pose, 480, 640)
    exact = exact_corners_px(0.174, 1.0, CAMERA.fx, CAMERA.fy, CAMERA.cx - CAMERA.fx * offset_m, CAMERA.cy)
    local = exact - crop.origin_px
    top = edge_points(crop.radiance, 0.5, "top", (local[0][0] + 10, local[1][0] - 10))
    left = edge_points(crop.radiance, 0.5, "left", (local[0][1] + 10, local[2][1] - 10))
    assert np.median(crop.radiance) in (0.0, 1.0) and crop.radiance.max() == 1.0
    assert np.mean(top[:, 1]) == pytest.approx(local[0][1], abs=0.1)
    assert np.mean(left[:, 0]) == pytest.approx(local[0][0], abs=0.1)


def test_blender_refuses_what_it_cannot_draw():
    with pytest.raises(ValueError, match="camera.distortion"):
        render_blender(SQUARE, CAMERA.model_copy(update={"distortion": [0.01, 0, 0, 0]}),
                       CameraPose(np.zeros(3), np.eye(3)), 480, 640)
    with pytest.raises(ValueError, match="camera.cx"):
        render_blender(SQUARE, CAMERA.model_copy(update={"cx": 250.0}), CameraPose(np.zeros(3), np.eye(3)), 480, 640)
