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


def _box_times_gaussian(columns, edge_px, sigma_px):
    """A rising straight edge at `edge_px` blurred by a Gaussian PSF and integrated over each 1 px column."""
    from scipy.special import ndtr
    from scipy.stats import norm

    def integral(u):  # of ndtr
        return u * ndtr(u) + norm.pdf(u)

    return sigma_px * (integral((columns + 0.5 - edge_px) / sigma_px) - integral((columns - 0.5 - edge_px) / sigma_px))


def _crossing(profile, level):
    i = int(np.nonzero(profile >= level)[0][0])
    return i - 1 + (level - profile[i - 1]) / (profile[i] - profile[i - 1])


@pytest.mark.parametrize("sigma_px", [0.8, 1.5])
def test_blender_frame_pixels_are_the_box_times_the_psf(sigma_px):
    """`render_blender_frame`'s pixel filter draws the sensor's pixel (1 px box) blurred by the PSF: a clipped
    edge's low crossing (a 4x overexposed panel read at half the clip level) lies where the analytic profile
    puts it. Cycles' 3 px Gaussian filter plus a PSF sampled at whole pixels put it ~0.2 px outside."""
    from simulator.blender import FRAME_SETTINGS, sensor_pixel_filter
    from simulator.render import SensorModel

    offset_m = 0.0013
    pose = CameraPose(np.array([offset_m, 0.0, 0.0]), np.eye(3))
    settings = sensor_pixel_filter(SensorModel(psf_sigma_px=sigma_px), FRAME_SETTINGS)
    crop = render_blender(SQUARE, CAMERA, pose, 480, 640, settings)
    exact = exact_corners_px(0.174, 1.0, CAMERA.fx, CAMERA.fy, CAMERA.cx - CAMERA.fx * offset_m, CAMERA.cy) - crop.origin_px
    left_px = exact[:, 0].min()
    rows = np.arange(int(exact[:, 1].min()) + 10, int(exact[:, 1].max()) - 10)
    level = 0.125
    expected = _crossing(_box_times_gaussian(np.arange(crop.radiance.shape[1], dtype=float), left_px, sigma_px), level)
    measured = np.mean([_crossing(crop.radiance[row], level) for row in rows])
    assert measured == pytest.approx(expected, abs=0.02)
