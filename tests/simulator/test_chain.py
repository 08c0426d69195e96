"""The phone image chain (simulator/chain.py): each stage on a simple scene, then the chain in a scene."""

import math

import cv2
import numpy as np
import pytest
from scipy.stats import norm

from simulator import chain as ch
from simulator.render import CameraPose, render_signal
from simulator.scene import Scene, SensorSpec, render_sample, scene_emitters

RNG = np.random.default_rng
MI8_FOCAL_M, MI8_PITCH_M = 3.52e-3, 0.9e-6


def crossing(profile: np.ndarray, level: float) -> float:
    """Where a rising profile first crosses `level`, linear between samples (in samples)."""
    i = int(np.argmax(profile >= level))
    return i - 1 + (level - profile[i - 1]) / (profile[i] - profile[i - 1])


# --- 1. optics -----------------------------------------------------------------------------------


@pytest.mark.parametrize("distance_m, focus_m", [(1.0, 0.5), (1.0, 3.0), (2.0, 1.0), (1.5, 1e4)])
def test_circle_of_confusion_is_the_thin_lens_blur_disc(distance_m, focus_m):
    f, n = MI8_FOCAL_M, 2.0
    image = lambda s: 1 / (1 / f - 1 / s)  # noqa: E731  thin lens: 1/f = 1/s + 1/v
    v_focus, v_point = image(focus_m), image(distance_m)
    # the cone from the aperture (diameter f / N) to the point's image, cut by the sensor at v_focus
    expected_m = (f / n) * abs(v_focus - v_point) / v_point
    assert ch.circle_of_confusion_px(distance_m, focus_m, n, f, MI8_PITCH_M) == pytest.approx(expected_m / MI8_PITCH_M)


def test_circle_of_confusion_of_the_mi8_front_camera():
    assert ch.circle_of_confusion_px(1.0, 1.0, 2.0, MI8_FOCAL_M, MI8_PITCH_M) == 0.0
    assert ch.circle_of_confusion_px(1.0, None, 2.0, MI8_FOCAL_M, MI8_PITCH_M) == 0.0
    # focused far away, a panel at 1 m blurs over f^2 / (N s) = 6.2 um = 6.9 native pixels
    assert ch.circle_of_confusion_px(1.0, 1e6, 2.0, MI8_FOCAL_M, MI8_PITCH_M) == pytest.approx(6.88, abs=0.01)


@pytest.mark.parametrize("diameter", [0.5, 1.5, 4.0, 9.3])
def test_pillbox_kernel_has_the_disc_support_and_unit_energy(diameter):
    kernel = ch.pillbox_kernel(diameter).astype(float)
    radius = diameter / 2
    assert kernel.sum() == pytest.approx(1.0, abs=1e-6)
    assert kernel.shape[0] == kernel.shape[1] and kernel.shape[0] % 2 == 1
    half = kernel.shape[0] // 2
    y, x = np.mgrid[-half : half + 1, -half : half + 1]
    nearest = np.hypot(np.maximum(np.abs(x) - 0.5, 0), np.maximum(np.abs(y) - 0.5, 0))
    assert np.all(kernel[nearest > radius] == 0)  # nothing beyond the disc
    if diameter > 2:
        # a uniform disc: flat inside, E[x^2] = r^2 / 4 (+ 1/12 for the pixels' own width)
        inner = np.hypot(np.abs(x) + 0.5, np.abs(y) + 0.5) <= radius
        assert np.ptp(kernel[inner]) < 1e-6 and kernel[inner][0] == pytest.approx(1 / (math.pi * radius**2), rel=0.05)
        assert (kernel * x**2).sum() == pytest.approx(radius**2 / 4 + 1 / 12, rel=0.05)


def test_defocus_spreads_a_point_into_the_disc_and_keeps_the_light():
    image = np.zeros((41, 41), np.float32)
    image[20, 20] = 1000.0
    blurred = ch.defocus(image, 7.0)
    assert blurred.sum() == pytest.approx(1000.0, rel=1e-5)
    lit = np.argwhere(blurred > 1e-6) - 20
    assert np.hypot(*lit.T).max() <= 3.5 + 0.75
    np.testing.assert_allclose(blurred[17:24, 17:24], 1000.0 * ch.pillbox_kernel(7.0), rtol=1e-5)
    assert ch.defocus(image, 0.0) is image


def test_veiling_glare_keeps_the_light_and_lifts_the_dark():
    image = np.zeros((60, 80), np.float32)
    image[20:30, 30:40] = 500.0
    glared = ch.veiling_glare(image, 0.02)
    assert glared.sum() == pytest.approx(image.sum(), rel=1e-5)
    assert glared[0, 0] == pytest.approx(0.02 * image.mean(), rel=1e-5)
    assert glared[25, 35] == pytest.approx(0.98 * 500 + 0.02 * image.mean(), rel=1e-5)


def test_halo_is_a_wide_low_gaussian_tail():
    image = np.zeros((241, 241), np.float32)
    image[113:128, 113:128] = 1000.0  # a 15 px square source centred on (120, 120)
    fraction, sigma = 0.05, 24.0  # computed on a grid 3x coarser
    haloed = ch.halo(image, fraction, sigma)
    assert haloed.sum() == pytest.approx(image.sum(), rel=0.01)
    assert haloed[120, 120] == pytest.approx(950.0, rel=0.01)  # the core keeps (1 - fraction) of the light

    def tail(x, y):  # fraction x the square convolved with a 2-D Gaussian of sigma
        across = lambda u: norm.cdf((u - 112.5) / sigma) - norm.cdf((u - 127.5) / sigma)  # noqa: E731
        return fraction * 1000.0 * across(x) * across(y)

    for r in (24, 48, 72):
        assert haloed[120, 120 + r] == pytest.approx(tail(120 + r, 120), rel=0.03)
        assert haloed[120 - r, 120] == pytest.approx(tail(120, 120 - r), rel=0.03)
    for r in (24, 48):
        assert haloed[120 + r, 120 + r] == pytest.approx(tail(120 + r, 120 + r), rel=0.03)


# --- 2. the sensor -------------------------------------------------------------------------------


def test_bayer_mosaic_samples_rggb_and_quad_bayer():
    scene = np.empty((8, 8, 3), np.float32)
    scene[...] = [10.0, 20.0, 30.0]
    raw = ch.bayer_mosaic(scene)
    assert (raw[0::2, 0::2] == 10).all() and (raw[0::2, 1::2] == 20).all()
    assert (raw[1::2, 0::2] == 20).all() and (raw[1::2, 1::2] == 30).all()
    quad = ch.bayer_mosaic(scene, quad=True)
    assert (quad[0:2, 0:2] == 10).all() and (quad[0:2, 2:4] == 20).all() and (quad[2:4, 2:4] == 30).all()
    np.testing.assert_array_equal(ch.bin2x2(quad), raw[:4, :4])  # 4-in-1 binning makes it RGGB
    grey = np.full((4, 6), 7.0, np.float32)
    np.testing.assert_array_equal(ch.bayer_mosaic(grey), grey)


@pytest.mark.parametrize("iso", [100, 400])
def test_shot_and_read_noise_at_the_chosen_iso(iso):
    model = SensorSpec(iso=iso).model()
    signal = np.full((256, 256), 104.0, np.float32)  # 100 DN of light above a 4 DN black level
    rng = RNG(1)
    electrons = ch.shot_noise(ch.to_electrons(signal, model.electrons_per_dn, 4.0), rng)
    assert electrons.mean() == pytest.approx(100 * model.electrons_per_dn, rel=0.01)
    assert electrons.var() == pytest.approx(100 * model.electrons_per_dn, rel=0.05)  # Poisson: variance = mean
    dn = ch.read_out(electrons, model.electrons_per_dn, model.read_noise_dn, 4.0, 255.0, rng)
    assert dn.mean() == pytest.approx(104.0, abs=0.1)
    assert dn.var() == pytest.approx(100 / model.electrons_per_dn + model.read_noise_dn**2, rel=0.05)


def test_full_well_clips_the_charge_below_the_adc_at_low_iso():
    model = SensorSpec(iso=25).model()  # 64 e-/DN: the 4080 e- well fills at 63.75 DN
    signal = np.full((32, 32), 500.0, np.float32)
    electrons = ch.full_well(ch.shot_noise(ch.to_electrons(signal, model.electrons_per_dn, 4.0), RNG(0)), 4080.0)
    assert electrons.max() == 4080.0
    dn = ch.read_out(electrons, model.electrons_per_dn, 0.0, 4.0, 255.0, RNG(0))
    assert np.all(dn == pytest.approx(4080.0 / 64 + 4.0))
    at_base = ch.read_out(np.full((2, 2), 4080.0 * 4), 16.0, 0.0, 4.0, 255.0, RNG(0))
    assert np.all(at_base == 255.0)  # above the ADC's range: clipped at saturation


def test_binning_halves_the_size_averages_and_halves_the_noise():
    raw = np.arange(24, dtype=np.float32).reshape(4, 6)
    binned = ch.bin2x2(raw)
    assert binned.shape == (2, 3)
    assert binned[0, 0] == pytest.approx((0 + 1 + 6 + 7) / 4) and binned[1, 2] == pytest.approx((16 + 17 + 22 + 23) / 4)
    noise = RNG(2).standard_normal((512, 512)).astype(np.float32)
    assert ch.bin2x2(noise).std() == pytest.approx(0.5, rel=0.03)


def test_quantize_raw_uses_the_adc_codes():
    codes = ch.quantize_raw(np.array([0.0, 127.5, 255.0, 300.0]), 10, 255.0)
    assert codes.dtype == np.uint16 and codes.tolist() == [0, 512, 1023, 1023]


# --- 3. the ISP ----------------------------------------------------------------------------------


def test_demosaic_returns_a_colour_patch_and_a_grey_step():
    colour = np.empty((16, 16, 3), np.float32)
    colour[...] = [60.0, 120.0, 200.0]
    codes = ch.quantize_raw(ch.bayer_mosaic(colour), 10, 255.0)
    for method in ("bilinear", "edge_aware"):
        rgb = ch.demosaic(codes, 10, 255.0, method)
        np.testing.assert_allclose(rgb[2:-2, 2:-2], colour[2:-2, 2:-2], atol=0.2)  # OpenCV's naming is RGGB here
    step = np.full((16, 32), 40.0, np.float32)
    step[:, 16:] = 200.0  # the edge at x = 15.5
    luma = ch.luma_bt601(ch.demosaic(ch.quantize_raw(ch.bayer_mosaic(step), 10, 255.0), 10, 255.0))
    far = np.r_[2:14, 18:30]
    np.testing.assert_allclose(luma[2:-2, far], step[2:-2, far], atol=0.2)  # exact away from the edge
    assert np.abs(luma[2:-2] - step[2:-2]).max() < 0.3 * 160  # the colour fringe beside it
    assert crossing(luma[8], 120.0) == pytest.approx(15.5, abs=0.25)


def test_noise_reduction_smooths_flat_noise_and_the_bilateral_keeps_an_edge():
    noise = 100 + 4 * RNG(3).standard_normal((128, 128)).astype(np.float32)
    assert ch.reduce_noise(noise, "off") is not None and ch.reduce_noise(noise, "off").std() == pytest.approx(
        4, rel=0.05
    )
    # a Gaussian of sigma 1 leaves 1 / (2 sigma sqrt(pi)) = 0.28 of white noise's deviation
    assert ch.reduce_noise(noise, "gaussian", 1.0).std() == pytest.approx(4 * 0.282, rel=0.1)
    step = np.full((32, 32), 50.0, np.float32)
    step[:, 16:] = 200.0
    kept = ch.reduce_noise(step + RNG(4).standard_normal((32, 32)).astype(np.float32), "bilateral", 1.0, 6.0)
    assert np.abs(kept[:, 14:18] - step[:, 14:18]).max() < 4  # the 150 DN edge is not smoothed


def test_tone_curves():
    v = np.linspace(0, 1, 1001)
    np.testing.assert_array_equal(ch.tone_curve(v, "linear"), v)
    assert ch.tone_curve(np.array([0.5]), "srgb")[0] == pytest.approx(0.7354, abs=1e-4)
    assert ch.tone_curve(np.array([0.0031308]), "srgb")[0] == pytest.approx(0.04045, abs=1e-5)
    s = ch.s_curve(v, 4.0)
    assert (s[0], s[500], s[-1]) == pytest.approx((0.0, 0.5, 1.0)) and np.all(np.diff(s) > 0)
    assert s[250] < 0.25 and s[750] > 0.75  # darker shadows, brighter highlights


@pytest.mark.parametrize("kind", ["linear", "srgb", "s_curve"])
@pytest.mark.parametrize("overexposure", [0.9, 4.0])
def test_a_tone_curve_moves_the_50_percent_crossing_of_a_clipped_edge_as_it_says(kind, overexposure):
    """Light P * Phi(x / sigma) clipped at saturation: after the curve the output's 50 % crossing is
    where the light equals the curve's inverse of 0.5, x = sigma * Phi^-1(curve^-1(0.5) * 255 / P)."""
    sigma, dx = 1.0, 0.01  # edge sampled at 1/100 of sigma
    x = np.arange(-600, 601) * dx
    light = (255.0 * overexposure * norm.cdf(x / sigma)).astype(np.float32)[None, :]
    out = ch.apply_tone_curve(light, kind, 255.0)[0]
    grid = np.linspace(0, 1, 100001)
    inverse_half = np.interp(0.5, ch.tone_curve(grid, kind), grid)
    expected = sigma * norm.ppf(inverse_half / overexposure)
    assert x[0] + crossing(out, 127.5) * dx == pytest.approx(expected, abs=0.01)
    if kind == "srgb":  # the gamma moves the clipped edge's 50 % out by about 0.5 sigma at 4x
        linear = sigma * norm.ppf(0.5 / overexposure)
        assert expected - linear == pytest.approx(
            norm.ppf(0.214 / overexposure) - norm.ppf(0.5 / overexposure), abs=1e-2
        )


@pytest.mark.parametrize("amount, sigma", [(0.5, 1.0), (1.0, 1.5)])
def test_sharpening_overshoots_by_the_unsharp_masks_amount(amount, sigma):
    """A step of height h between pixels: the first pixel beside it sees the blurred step at
    h (1 + g0) / 2 (g0 the discrete Gaussian's centre tap), so it overshoots by amount h (1 - g0) / 2."""
    step = np.full((8, 64), 50.0, np.float32)
    step[:, 32:] = 150.0
    out = ch.sharpen(step, amount, sigma)
    ksize = int(round(sigma * 4 * 2 + 1)) | 1  # OpenCV's kernel size for float images
    g0 = float(cv2.getGaussianKernel(ksize, sigma, cv2.CV_32F)[ksize // 2, 0])
    overshoot = amount * 100.0 * (1 - g0) / 2
    assert out[4, 32] - 150.0 == pytest.approx(overshoot, abs=1e-3)
    assert 50.0 - out[4, 31] == pytest.approx(overshoot, abs=1e-3)  # and the undershoot on the dark side
    assert out[4, :20] == pytest.approx(50.0) and out[4, 44:] == pytest.approx(150.0)  # flat parts untouched
    np.testing.assert_array_equal(ch.sharpen(step, 0.0), step)


def test_luma_uses_the_bt601_weights():
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [100, 100, 100]]], np.float32)
    np.testing.assert_allclose(ch.luma_bt601(rgb)[0], [76.245, 149.685, 29.07, 100.0], rtol=1e-6)


# --- 4. JPEG -------------------------------------------------------------------------------------


@pytest.mark.parametrize("quality, tolerance", [(95, 2), (75, 4)])
def test_jpeg_keeps_a_flat_patch_within_a_few_dn(quality, tolerance):
    frame = np.full((64, 96), 90, np.uint8)
    frame[16:48, 48:80] = 255  # a clipped panel beside the flat patch
    decoded = ch.jpeg_roundtrip(frame, quality)
    assert decoded.shape == frame.shape and decoded.dtype == np.uint8
    assert np.abs(decoded[8:56, 4:36].astype(int) - 90).max() <= tolerance
    assert np.abs(decoded[20:44, 52:76].astype(int) - 255).max() <= tolerance


# --- the chain in a scene ------------------------------------------------------------------------

SMALL = {
    "name": "small",
    "room": {"size_m": [2.0, 2.0, 1.0], "origin_m": [-1.0, -1.0, 0.0]},
    "beacons": [{"id": 3, "center_m": [0.0, 0.0, 1.0], "luminance_nits": 200.0}],  # 204 DN: below saturation
    "camera": {"profile": "xiaomi-mi8-front", "scale": 0.1},
    "sensor": {"electrons_per_dn_iso100": 1e7, "read_noise_dn_iso100": 0.0},  # quiet
}
IDEAL = {
    "optics": {"glare_fraction": 0.0, "halo_fraction": 0.0},
    "pixels": {"bayer": False, "raw_bits": 16, "full_well_e": 1e12},
}  # the quiet sensor's 1e7 e-/DN
POSE = CameraPose(np.array([0.0123, -0.0071, 0.0]), np.eye(3))


def scene(chain=None, **changes) -> Scene:
    return Scene.model_validate({**SMALL, **changes, "chain": chain})


def light_moments(frame: np.ndarray, background: float) -> tuple[float, float, float]:
    light = frame.astype(float) - background
    y, x = np.indices(frame.shape)
    return light.sum(), (light * x).sum() / light.sum(), (light * y).sum() / light.sum()


def test_without_a_chain_the_scene_file_and_frames_are_as_before():
    plain = scene()
    assert "chain" not in plain.to_json()
    with_chain = scene(chain={})
    assert Scene.model_validate_json(with_chain.to_json()) == with_chain
    assert with_chain.chain.optics.f_number == 2.0 and with_chain.chain.isp.tone_curve == "linear"
    assert with_chain.chain.pixels.full_well_e == 4080.0 and with_chain.chain.jpeg_quality is None


@pytest.mark.parametrize(
    "chain, field",
    [
        ({"pixels": {"binning": 3}}, "binning"),
        ({"optics": {"glare_fraction": 1.5}}, "glare_fraction"),
        ({"isp": {"tone_curve": "log"}}, "tone_curve"),
        ({"jpeg_quality": 0}, "jpeg_quality"),
        ({"colour": True}, "colour"),
    ],
)
def test_a_bad_chain_names_the_knob(chain, field):
    with pytest.raises(ValueError, match=field):
        scene(chain=chain)


def test_an_ideal_chain_gives_the_renderers_light():
    """Glare, halo, Bayer off, a quiet sensor, a 16-bit ADC: the chain is the renderer's light, rounded."""
    ideal = scene(chain=IDEAL)
    frame, meta = render_sample(ideal, POSE, RNG(0))
    signal = render_signal(scene_emitters(ideal, POSE), meta.width, meta.height, ideal.sensor.model())
    assert np.abs(frame.astype(float) - signal).max() <= 0.51


def test_binning_keeps_the_frame_the_light_and_where_it_is():
    unbinned, _ = render_sample(scene(chain=IDEAL), POSE, RNG(0))
    binned, meta = render_sample(scene(chain={**IDEAL, "pixels": {**IDEAL["pixels"], "binning": 2}}), POSE, RNG(0))
    assert binned.shape == unbinned.shape == (meta.height, meta.width)
    background = SMALL["sensor"].get("black_level_dn", 4.0) + 4.0 * 0.01 * 102  # black level + ambient
    a, b = light_moments(unbinned, background), light_moments(binned, background)
    assert b[0] == pytest.approx(a[0], rel=2e-3)
    assert b[1:] == pytest.approx(a[1:], abs=0.02)


def test_defocus_follows_the_focus_distance_and_keeps_the_light():
    focused = scene(chain=IDEAL)
    near = scene(chain={**IDEAL, "optics": {**IDEAL["optics"], "focus_distance_m": 0.2}})  # a 2.8 px disc
    [panel] = scene_emitters(near, POSE)
    camera = near.camera.intrinsics()
    assert panel.defocus_px == pytest.approx(
        ch.circle_of_confusion_px(1.0, 0.2, 2.0, MI8_FOCAL_M, MI8_FOCAL_M / camera.fx), rel=1e-6
    )
    assert panel.defocus_px == pytest.approx(MI8_FOCAL_M**2 / 2 * 0.8 / (1.0 * (0.2 - MI8_FOCAL_M)) / 9e-6, rel=1e-6)
    assert scene_emitters(focused, POSE)[0].defocus_px == 0.0
    sharp, _ = render_sample(focused, POSE, RNG(0))
    soft, _ = render_sample(near, POSE, RNG(0))
    assert light_moments(soft, 8.08)[0] == pytest.approx(light_moments(sharp, 8.08)[0], rel=2e-3)
    # the left edge's line spread (derivative of the mean profile of the middle rows): a uniform disc of
    # radius r adds r^2 / 4 to its variance (+ 1 / 108 px^2: the disc drawn on the PSF's grid, 3x finer)
    rows = slice(int(camera.cy) - 15, int(camera.cy) + 15)
    centre = int(camera.cx - camera.fx * POSE.position_m[0])

    def spread_variance(frame):
        lsf = np.diff(frame[rows, centre - 60 : centre].astype(float).mean(axis=0))
        x = np.arange(len(lsf))
        mean = (lsf * x).sum() / lsf.sum()
        return (lsf * (x - mean) ** 2).sum() / lsf.sum()

    signal = lambda s: render_signal(scene_emitters(s, POSE), 388, 518, s.sensor.model())  # noqa: E731  no rounding
    added = spread_variance(signal(near)) - spread_variance(signal(focused))
    assert added == pytest.approx((panel.defocus_px / 2) ** 2 / 4 + 1 / 108, rel=0.05)


def test_a_phone_with_the_isp_on_and_jpeg_is_deterministic():
    phone = scene(
        chain={"isp": ch.IspSpec.phone().model_dump(), "jpeg_quality": 90},
        beacons=[{"id": 3, "center_m": [0.0, 0.0, 1.0]}],
        sensor={},
    )
    a, meta = render_sample(phone, POSE, RNG(5))
    b, _ = render_sample(phone, POSE, RNG(5))
    np.testing.assert_array_equal(a, b)
    assert a.shape == (meta.height, meta.width) and a.dtype == np.uint8
    assert a.max() == 255  # the clipped panel
    # the tone curve lifts the dark ceiling (8.08 DN of black level and ambient light) to 36 DN
    assert np.median(a) == pytest.approx(255 * ch.tone_curve(np.array(8.08 / 255), "s_curve"), abs=2)
    off, _ = render_sample(phone.model_copy(update={"chain": ch.ChainSpec()}), POSE, RNG(5))
    assert np.median(off) == 8
