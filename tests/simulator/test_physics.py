"""The renderer against exact geometry and the contract's physics (area, edges, rolling shutter)."""

import numpy as np
import pytest
from scipy.stats import norm

from server.vlc.codec import LedWaveform
from shared_schemas import Beacon, CameraIntrinsics
from simulator.bench_fidelity import edge_points, exact_corners_px
from simulator.led import row_gains
from simulator.render import CameraPose, SensorModel, beacon_outline_px, exact_polygon_area_px, render_frame

CAMERA = CameraIntrinsics(fx=977.78, fy=977.78, cx=239.5, cy=319.5)
SQUARE = Beacon(id=0, center_m=[0.0, 0.0, 1.0], side_m=0.174, corner_radius_m=0.0)
QUIET = dict(background_dn=10.0, electrons_per_dn=1e12, read_noise_dn=0.0)


def _render(beacon, pose, plateau_dn, psf_px=1.0, row_gain=None, seed=0):
    sensor = SensorModel(plateau_dn=plateau_dn, psf_sigma_px=psf_px, **QUIET)
    return render_frame(beacon, CAMERA, pose, 480, 640, sensor, np.random.default_rng(seed), row_gain).astype(float)


@pytest.mark.parametrize("ypr, shift", [((0, 0, 0), (0.0, 0.0)), ((17, 4, -3), (0.031, -0.047))])
def test_rendered_light_equals_the_exact_projected_area(ypr, shift):
    from server.geometry import rotation_from_ypr

    beacon = SQUARE.model_copy(update={"corner_radius_m": 0.02})
    pose = CameraPose(np.array([shift[0], shift[1], 0.0]), rotation_from_ypr(*ypr))
    image = _render(beacon, pose, plateau_dn=200.0)  # below saturation: nothing clipped
    area_px = exact_polygon_area_px(beacon_outline_px(beacon, CAMERA, pose, max_step_px=0.05))
    # whole DN rounding adds at most +-0.5 DN per pixel, averaging out
    assert (image - 10.0).sum() / 200.0 == pytest.approx(area_px, rel=2e-4)


@pytest.mark.parametrize("offset_m", [0.0, 0.00037, 0.00081])  # sub-pixel phases of the edges
def test_unclipped_edges_lie_on_the_exact_projection_at_the_50_percent_level(offset_m):
    pose = CameraPose(np.array([offset_m, -offset_m * 0.7, 0.0]), np.eye(3))
    image = _render(SQUARE, pose, plateau_dn=200.0)
    exact = exact_corners_px(0.174, 1.0, CAMERA.fx, CAMERA.fy, CAMERA.cx - CAMERA.fx * offset_m,
                             CAMERA.cy + CAMERA.fy * offset_m * 0.7)
    level = 10.0 + 200.0 / 2
    (x0, y0), (x1, _), (_, y2) = exact[0], exact[1], exact[2]
    top = edge_points(image, level, "top", (x0 + 10, x1 - 10))
    left = edge_points(image, level, "left", (y0 + 10, y2 - 10))
    assert len(top) > 100 and len(left) > 100
    assert np.mean(top[:, 1] - y0) == pytest.approx(0.0, abs=0.05)
    assert np.mean(left[:, 0] - x0) == pytest.approx(0.0, abs=0.05)


@pytest.mark.parametrize("overexposure", [2.0, 4.0, 8.0])
def test_clipped_edges_move_out_as_the_blurred_pixel_step_predicts(overexposure):
    """The contract's physics: a clipped edge's 50 % level lies outside the true edge.

    Expected: the step integrated over a pixel and blurred by the PSF, f(d) = mean over the pixel
    box of Phi(-(d + u) / sigma), sampled at the pixel centres, clipped and read at the 50 % level
    with the same linear interpolation as the measurement.
    """
    plateau = 255.0 * overexposure
    image = _render(SQUARE, CameraPose(np.zeros(3), np.eye(3)), plateau_dn=plateau)
    exact = exact_corners_px(0.174, 1.0, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    level = (10.0 + 255.0) / 2
    top = edge_points(image, level, "top", (exact[0][0] + 10, exact[1][0] - 10))
    rows = np.arange(200, 260)
    box = np.linspace(-0.5, 0.5, 401)
    share = norm.cdf(-(exact[0][1] - rows[:, None] + box[None, :]) / 1.0).mean(axis=1)  # inside share per row
    profile = np.minimum(10.0 + plateau * share, 255.0)
    k = np.nonzero(profile >= level)[0][0]
    expected_y = rows[k - 1] + (level - profile[k - 1]) / (profile[k] - profile[k - 1])
    assert np.mean(top[:, 1]) == pytest.approx(expected_y, abs=0.03)
    assert exact[0][1] - np.mean(top[:, 1]) > 0.5  # outside the true edge by more than half a pixel


def _stripe_profile(exposure_s: float, row_time_s: float) -> np.ndarray:
    """Mean row values inside the panel of a 2.5 kHz square wave seen with a rolling shutter."""
    square_wave = LedWaveform(chips=(1, 0), chip_rate_hz=5000.0, low_level=0.0, high_level=1.0)  # 2.5 kHz
    gains = row_gains(square_wave, 640, row_time_s, exposure_s)
    beacon = SQUARE.model_copy(update={"side_m": 0.4})  # 391 rows tall
    image = _render(beacon, CameraPose(np.zeros(3), np.eye(3)), plateau_dn=200.0, row_gain=gains)
    return image[140:500, 200:280].mean(axis=1)


def test_long_exposure_averages_the_code_away_and_a_short_one_stripes_at_its_period():
    row_time_s = 0.03 / 639  # 30 ms skew over 640 rows: 8.5 rows per 0.4 ms period
    steady = _stripe_profile(0.010, row_time_s)  # 10 ms = 25 periods
    assert np.ptp(steady) < 1.0 and np.mean(steady) == pytest.approx(10 + 100, abs=1)
    striped = _stripe_profile(1 / 8000, row_time_s)
    assert np.ptp(striped) > 100  # full-depth stripes: the window is a third of a period
    spectrum = np.abs(np.fft.rfft(striped - striped.mean()))
    frequencies = np.fft.rfftfreq(len(striped))
    period_rows = 1 / frequencies[np.argmax(spectrum)]
    assert period_rows == pytest.approx(0.4e-3 / row_time_s, rel=0.03)


def test_a_moving_camera_shears_the_panel_by_the_row_readout():
    """Rolling shutter geometry: row r is seen from where the camera is at r * row_time + exposure / 2."""
    from simulator.render import Emitter, ReadoutMotion, render_emitters, world_polygon_px

    row_time_s, exposure_s, speed_mps = 0.03 / 639, 0.001, 2.0
    motion = ReadoutMotion(np.array([speed_mps, 0.0, 0.0]), np.zeros(3), row_time_s, exposure_s)
    pose = CameraPose(np.zeros(3), np.eye(3))
    corners = np.array([[-0.087, -0.087, 1.0], [0.087, -0.087, 1.0], [0.087, 0.087, 1.0], [-0.087, 0.087, 1.0]])
    outline = world_polygon_px(corners, CAMERA, pose, 480, 640, 0.5, motion)
    sensor = SensorModel(plateau_dn=200.0, psf_sigma_px=1.0, **QUIET)
    image = render_emitters([Emitter(outline, 200.0)], 480, 640, sensor, np.random.default_rng(0)).astype(float)
    left = edge_points(image, 110.0, "left", (250, 390))
    slope, offset = np.polyfit(left[:, 1], left[:, 0], 1)
    # the camera moves +X, so the panel moves -x in later rows: x(r) = x0 - fx v (r t_row + t_exp / 2) / Z
    assert slope == pytest.approx(-CAMERA.fx * speed_mps * row_time_s, rel=0.02)
    expected_at_320 = CAMERA.cx - CAMERA.fx * 0.087 - CAMERA.fx * speed_mps * (320 * row_time_s + exposure_s / 2)
    assert slope * 320 + offset == pytest.approx(expected_at_320, abs=0.05)
