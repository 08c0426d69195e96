"""The renderer against exact geometry."""

import numpy as np
import pytest

from server.geometry import rotation_from_ypr
from shared_schemas import Beacon, CameraIntrinsics
from simulator.render import CameraPose, SensorModel, beacon_outline_px, coverage_map, exact_polygon_area_px, render_frame

CAMERA = CameraIntrinsics(fx=977.78, fy=977.78, cx=159.5, cy=119.5)
BEACON = Beacon(id=0, center_m=[0, 0, 1.0], side_m=0.174, corner_radius_m=0.02)


def test_rectangle_coverage_is_exact():
    rect = np.array([[2.3, 1.25], [7.6, 1.25], [7.6, 4.75], [2.3, 4.75]])
    cover = coverage_map(rect, 10, 6, subrows=4)
    x_share = np.clip(np.minimum(np.arange(10) + 0.5, 7.6) - np.maximum(np.arange(10) - 0.5, 2.3), 0, 1)
    y_share = np.clip(np.minimum(np.arange(6) + 0.5, 4.75) - np.maximum(np.arange(6) - 0.5, 1.25), 0, 1)
    np.testing.assert_allclose(cover, np.outer(y_share, x_share), atol=1e-6)


def test_coverage_sums_to_the_polygon_area():
    far = BEACON.model_copy(update={"center_m": [0, 0, 2.0]})
    pose = CameraPose(np.array([0.05, -0.03, 0.0]), rotation_from_ypr(20, 2, -1))
    outline = beacon_outline_px(far, CAMERA, pose)
    assert outline.min() > 0 and outline[:, 0].max() < 320 and outline[:, 1].max() < 240
    cover = coverage_map(outline, 320, 240)
    assert cover.sum() == pytest.approx(exact_polygon_area_px(outline), rel=1e-3)
    assert cover.max() == pytest.approx(1.0, abs=1e-5) and cover[0, 0] == 0


def test_outline_of_a_centred_beacon_has_the_pinhole_size():
    outline = beacon_outline_px(BEACON, CAMERA, CameraPose(np.zeros(3), np.eye(3)))
    assert outline.mean(axis=0) == pytest.approx([159.5, 119.5], abs=0.05)
    assert np.ptp(outline[:, 0]) == pytest.approx(977.78 * 0.174, abs=1e-3)


def test_unclipped_edge_mid_level_lies_on_the_true_edge():
    pose = CameraPose(np.array([0.0, 0.0, 0.0]), np.eye(3))
    sensor = SensorModel(background_dn=10, plateau_dn=200, psf_sigma_px=1.0, electrons_per_dn=1e9, read_noise_dn=0)
    image = render_frame(BEACON, CAMERA, pose, 320, 240, sensor, np.random.default_rng(0)).astype(float)
    # quantisation to whole DN limits this check to ~0.01 px; the true left edge is at cx - f s / 2
    row = image[120]
    level = (10 + 210) / 2
    j = int(np.nonzero(row >= level)[0][0])
    crossing = j - 1 + (level - row[j - 1]) / (row[j] - row[j - 1])
    assert crossing == pytest.approx(159.5 - 977.78 * 0.174 / 2, abs=0.05)


def test_render_is_deterministic_and_saturates():
    pose = CameraPose(np.zeros(3), np.eye(3))
    a = render_frame(BEACON, CAMERA, pose, 320, 240, SensorModel(), np.random.default_rng(3))
    b = render_frame(BEACON, CAMERA, pose, 320, 240, SensorModel(), np.random.default_rng(3))
    assert a.dtype == np.uint8 and a.shape == (240, 320)
    np.testing.assert_array_equal(a, b)
    assert a[120, 160] == 255 and abs(a[:10, :10].mean() - 8.0) < 1.0


def test_beacon_behind_the_camera_is_an_error():
    with pytest.raises(ValueError, match="front of the camera"):
        beacon_outline_px(BEACON, CAMERA, CameraPose(np.array([0, 0, 2.0]), np.eye(3)))


def test_row_gain_scales_the_panel_per_row_and_not_the_background():
    pose = CameraPose(np.zeros(3), np.eye(3))
    sensor = SensorModel(background_dn=10, plateau_dn=200, psf_sigma_px=0.0, electrons_per_dn=1e9, read_noise_dn=0)
    gain = np.where(np.arange(240) % 2 == 0, 1.0, 0.5)
    image = render_frame(BEACON, CAMERA, pose, 320, 240, sensor, np.random.default_rng(0), row_gain=gain)
    assert image[120, 160] == 210 and image[121, 160] == 110 and image[121, 5] == 10
    with pytest.raises(ValueError, match="row_gain"):
        render_frame(BEACON, CAMERA, pose, 320, 240, sensor, np.random.default_rng(0), row_gain=np.ones(10))
