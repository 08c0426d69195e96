"""A phone's image chain, from the light on the sensor to the luma the server gets (issue 13, item 1).

The renderer (`simulator.render`) draws the light: exact pixel coverage, the lens's Gaussian PSF,
vignetting, the rolling shutter. Without a chain (`Scene.chain` none) it adds Gaussian noise and
clips at 8 bits, as it always has. With a chain the same noiseless light goes through the stages
below, in the order a camera applies them; each is a small pure function (arrays in, arrays out):

1. optics: `defocus` (a disc, `pillbox_kernel`, of the thin-lens circle of confusion,
   `circle_of_confusion_px`; applied per panel by the renderer, since it depends on each panel's
   depth), `veiling_glare`, `halo`;
2. the sensor: `bayer_mosaic`, `to_electrons`, `shot_noise`, `full_well`, `read_out`, `bin2x2`,
   `quantize_raw`;
3. the ISP: `demosaic`, `reduce_noise`, `apply_tone_curve`, `luma_bt601`, `sharpen` (on the luma,
   as phone ISPs sharpen in YUV after the tone curve), `to_u8`;
4. `jpeg_roundtrip`.

`develop` runs stages 1 (the frame-wide part) to 4 on a rendered signal. Levels are the
renderer's DN (8-bit scale, 255 = saturation; black level included, as the renderer has it).
Knobs and defaults: `ChainSpec` (docs/simulator.md, "Phone image chain").
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import cv2
import numpy as np
from pydantic import Field

from shared_schemas.models import Strict, ToneCurve
from simulator.motion import MotionSpec

Positive = Annotated[float, Field(gt=0)]
BT601 = (0.299, 0.587, 0.114)


# ---------------------------------------------------------------------------------------------
# the knobs


class OpticsSpec(Strict):
    """The lens. Defaults: the Mi 8 front camera (20 MP, f/2.0, 1.8 um binned pixels as its published
    specifications list it, e.g. Wikipedia's "Xiaomi Mi 8"; focal length 3.52 mm and 0.9 um native
    pixels from the device profile)."""

    f_number: Positive = Field(default=2.0, description="Mi 8 front camera: f/2.0")
    focus_distance_m: float | None = Field(
        default=None,
        gt=0,
        description="none: every panel in focus (the app asks Camera2 to focus at the ceiling distance)",
    )
    glare_fraction: float = Field(
        default=0.01,
        ge=0,
        lt=1,
        description="share of the frame's light scattered evenly over it (veiling glare index, ISO 9358)",
    )
    halo_fraction: float = Field(default=0.02, ge=0, lt=1, description="share of each source's light in a wide tail")
    halo_sigma_deg: Positive = Field(default=1.0, description="the tail's Gaussian width, degrees of field")


class PixelSpec(Strict):
    """The sensor behind the lens; exposure, ISO, electrons per DN and read noise are the scene's `sensor`."""

    bayer: bool = Field(default=True, description="an RGGB colour filter array (a Quad Bayer one when binning)")
    full_well_e: Positive = Field(
        default=4080.0,
        description="electrons: 255 DN x 16 e-/DN, the base ISO's range (4000-6000 e- is usual for 0.8-1.0 um pixels)",
    )
    raw_bits: int = Field(default=10, ge=8, le=16, description="the ADC: RAW10, usual for phone sensors")
    binning: Literal[1, 2] = Field(default=1, description="2: the frame is the 2x2 average of a sensor twice its size")


class IspSpec(Strict):
    """The image signal processor; every stage that Camera2 lets the app turn off is off."""

    demosaic: Literal["bilinear", "edge_aware"] = "bilinear"
    noise_reduction: Literal["off", "gaussian", "bilateral"] = "off"
    noise_sigma_px: Positive = Field(default=1.0, description="spatial width of the noise filter")
    noise_sigma_dn: Positive = Field(default=6.0, description="the bilateral filter's range width")
    sharpen_amount: float = Field(default=0.0, ge=0, description="unsharp mask gain; 0 = off")
    sharpen_sigma_px: Positive = 1.0
    tone_curve: Literal["linear", "srgb", "s_curve"] = "linear"
    s_curve_contrast: Positive = Field(default=4.0, description="the logistic S's slope (after sRGB)")

    @classmethod
    def phone(cls) -> IspSpec:
        """What a phone does when it is not told otherwise (Camera2's FAST / HIGH_QUALITY modes)."""
        return cls(demosaic="edge_aware", noise_reduction="bilateral", sharpen_amount=0.8, tone_curve="s_curve")


class ChainSpec(Strict):
    """A phone's image chain; `Scene.chain` none = the renderer's own 8-bit noise model."""

    optics: OpticsSpec = OpticsSpec()
    pixels: PixelSpec = PixelSpec()
    isp: IspSpec = IspSpec()
    jpeg_quality: int | None = Field(default=None, ge=1, le=100, description="none: the planes, no JPEG")
    motion: MotionSpec = Field(default=MotionSpec(), description="the phone moving during the frame (simulator.motion)")

    def reported_tone_curve(self) -> ToneCurve:
        """What the app reports in the frame's `tone_curve`: `linear` when its contrast curve held, `srgb` for
        the sRGB preset (its fallback, which the server undoes), `device` for the S-curve (a device's own)."""
        return {"linear": ToneCurve.linear, "srgb": ToneCurve.srgb}.get(self.isp.tone_curve, ToneCurve.device)


# ---------------------------------------------------------------------------------------------
# 1. optics


def circle_of_confusion_px(
    distance_m: float, focus_m: float | None, f_number: float, focal_length_m: float, pixel_pitch_m: float
) -> float:
    """Diameter in pixels of the thin lens's blur disc for a point at `distance_m` when focused at `focus_m`.

    c = (f / N) * f * |s - s_f| / (s * (s_f - f)): the aperture f / N, the image of s_f at
    v_f = f s_f / (s_f - f), the image of s at v_s; the cone from the aperture to v_s cut at v_f.
    """
    if focus_m is None or distance_m <= focal_length_m:
        return 0.0
    aperture_m = focal_length_m / f_number
    coc_m = aperture_m * focal_length_m * abs(distance_m - focus_m) / (distance_m * (focus_m - focal_length_m))
    return coc_m / pixel_pitch_m


def pillbox_kernel(diameter_px: float, supersample: int = 8) -> np.ndarray:
    """A disc of `diameter_px`, each kernel pixel weighted by its area inside the disc; sums to 1."""
    radius = diameter_px / 2
    half = int(math.ceil(radius - 0.5)) if radius > 0.5 else 0
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    grid = np.arange(-half, half + 1)
    fine = (grid[:, None] + offsets[None, :]).ravel()
    inside = (fine[:, None] ** 2 + fine[None, :] ** 2 <= radius**2).astype(np.float64)
    n = 2 * half + 1
    kernel = inside.reshape(n, supersample, n, supersample).mean(axis=(1, 3))
    if kernel.sum() == 0:  # a disc smaller than a sub-pixel: a point
        kernel[half, half] = 1.0
    return (kernel / kernel.sum()).astype(np.float32)


def defocus(image: np.ndarray, diameter_px: float) -> np.ndarray:
    """`image` blurred by the disc of `diameter_px` (light beyond the border as at the border)."""
    if diameter_px <= 1e-3:
        return image  # the same array: no copy, no change
    return cv2.filter2D(image.astype(np.float32), -1, pillbox_kernel(diameter_px), borderType=cv2.BORDER_REPLICATE)


def veiling_glare(image: np.ndarray, fraction: float) -> np.ndarray:
    """A `fraction` of the frame's light scattered evenly over the frame (the light's sum is kept)."""
    if fraction <= 0:
        return image
    return ((1 - fraction) * image + fraction * float(image.mean())).astype(np.float32)


def halo(image: np.ndarray, fraction: float, sigma_px: float) -> np.ndarray:
    """A `fraction` of each pixel's light spread as a wide Gaussian of `sigma_px` (the PSF's tail).

    Blurred on a grid about sigma / 8 times coarser and resized back (the tail is smooth), so a
    wide tail costs little on a full frame.
    """
    if fraction <= 0:
        return image
    image = image.astype(np.float32)
    height, width = image.shape[:2]
    step = max(1, int(sigma_px // 8))
    rows, cols = -(-height // step), -(-width // step)  # whole blocks: the coarse grid lines up with the fine one
    padded = cv2.copyMakeBorder(image, 0, rows * step - height, 0, cols * step - width, cv2.BORDER_REPLICATE)
    small = cv2.resize(padded, (cols, rows), interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), sigma_px / step, borderType=cv2.BORDER_REPLICATE)
    if step > 1:
        small = cv2.resize(small, (cols * step, rows * step), interpolation=cv2.INTER_LINEAR)
    tail = small[:height, :width]
    return ((1 - fraction) * image + fraction * tail).astype(np.float32)


# ---------------------------------------------------------------------------------------------
# 2. the sensor


def bayer_mosaic(scene: np.ndarray, quad: bool = False) -> np.ndarray:
    """What an RGGB colour filter array lets each pixel see: (H, W) from a colour scene (H, W, 3).

    A grey scene (H, W) is what every channel sees (white-balanced), so it passes unchanged.
    `quad`: each colour covers a 2x2 block (Quad Bayer), so that 2x2 binning gives RGGB.
    """
    if scene.ndim == 2:
        return scene.astype(np.float32)
    height, width = scene.shape[:2]
    rows = np.arange(height) // (2 if quad else 1) % 2
    cols = np.arange(width) // (2 if quad else 1) % 2
    channel = np.array([[0, 1], [1, 2]])[rows[:, None], cols[None, :]]  # R G / G B
    return np.take_along_axis(scene, channel[..., None], axis=2)[..., 0].astype(np.float32)


def to_electrons(signal_dn: np.ndarray, electrons_per_dn: float, black_level_dn: float) -> np.ndarray:
    """The mean charge of each pixel: the light above the black level (an offset, not charge)."""
    return np.maximum(signal_dn - black_level_dn, 0.0) * electrons_per_dn


def shot_noise(electrons: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Photon arrival: a Poisson count of mean `electrons`."""
    return rng.poisson(electrons).astype(np.float32)


def full_well(electrons: np.ndarray, capacity_e: float) -> np.ndarray:
    """A pixel holds at most `capacity_e` electrons."""
    return np.minimum(electrons, capacity_e)


def read_out(
    electrons: np.ndarray,
    electrons_per_dn: float,
    read_noise_dn: float,
    black_level_dn: float,
    saturation_dn: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """The charge as DN at the chosen ISO (gain sets `electrons_per_dn` and `read_noise_dn`), with
    read noise, the black level and the ADC's range [0, saturation]."""
    dn = electrons / electrons_per_dn + black_level_dn
    if read_noise_dn > 0:
        dn = dn + read_noise_dn * rng.standard_normal(dn.shape, dtype=np.float32)
    return np.clip(dn, 0.0, saturation_dn).astype(np.float32)


def bin2x2(raw: np.ndarray) -> np.ndarray:
    """Each 2x2 block's mean (a Quad Bayer sensor's 4-in-1 mode); odd edges are dropped."""
    height, width = raw.shape[0] // 2 * 2, raw.shape[1] // 2 * 2
    blocks = raw[:height, :width].reshape(height // 2, 2, width // 2, 2, *raw.shape[2:])
    return blocks.mean(axis=(1, 3)).astype(np.float32)


def quantize_raw(dn: np.ndarray, bits: int, saturation_dn: float) -> np.ndarray:
    """The ADC's codes (uint16, 0 .. 2^bits - 1) for DN in [0, saturation]."""
    top = (1 << bits) - 1
    return np.clip(np.rint(dn * (top / saturation_dn)), 0, top).astype(np.uint16)


# ---------------------------------------------------------------------------------------------
# 3. the ISP


def demosaic(codes: np.ndarray, bits: int, saturation_dn: float, method: str = "bilinear") -> np.ndarray:
    """RGB (H, W, 3) float32 DN from RGGB codes: OpenCV's bilinear or edge-aware interpolation."""
    code = {"bilinear": cv2.COLOR_BayerRGGB2RGB, "edge_aware": cv2.COLOR_BayerRGGB2RGB_EA}[method]
    rgb = cv2.cvtColor(np.ascontiguousarray(codes, dtype=np.uint16), code)
    return rgb.astype(np.float32) * (saturation_dn / ((1 << bits) - 1))


def reduce_noise(image: np.ndarray, method: str, sigma_px: float = 1.0, sigma_dn: float = 6.0) -> np.ndarray:
    """Noise reduction: none, a Gaussian of `sigma_px`, or a bilateral filter (edges of more than
    ~`sigma_dn` kept)."""
    image = image.astype(np.float32)
    if method == "off":
        return image
    if method == "gaussian":
        return cv2.GaussianBlur(image, (0, 0), sigma_px, borderType=cv2.BORDER_REPLICATE)
    diameter = 2 * int(math.ceil(2 * sigma_px)) + 1
    return cv2.bilateralFilter(image, diameter, sigma_dn, sigma_px, borderType=cv2.BORDER_REPLICATE)


def srgb(v: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) on linear [0, 1]."""
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)


def s_curve(v: np.ndarray, contrast: float) -> np.ndarray:
    """A logistic S through (0, 0), (0.5, 0.5), (1, 1): darker shadows, brighter highlights."""
    low, high = 1 / (1 + math.exp(contrast / 2)), 1 / (1 + math.exp(-contrast / 2))
    return (1 / (1 + np.exp(-contrast * (np.clip(v, 0.0, 1.0) - 0.5))) - low) / (high - low)


def tone_curve(v: np.ndarray, kind: str, contrast: float = 4.0) -> np.ndarray:
    """The tone curve on [0, 1]: linear (what the app asks for), sRGB, or sRGB then an S."""
    if kind == "linear":
        return np.clip(v, 0.0, 1.0)
    if kind == "srgb":
        return srgb(v)
    return s_curve(srgb(v), contrast)


def apply_tone_curve(image_dn: np.ndarray, kind: str, saturation_dn: float, contrast: float = 4.0) -> np.ndarray:
    """`tone_curve` on DN (the range [0, saturation])."""
    if kind == "linear":
        return np.clip(image_dn, 0.0, saturation_dn).astype(np.float32)
    return (saturation_dn * tone_curve(image_dn / saturation_dn, kind, contrast)).astype(np.float32)


def luma_bt601(rgb: np.ndarray) -> np.ndarray:
    """Y = 0.299 R + 0.587 G + 0.114 B (ITU-R BT.601, the luma of JPEG and of Camera2's YUV)."""
    if rgb.ndim == 2:
        return rgb.astype(np.float32)
    return (rgb.astype(np.float32) @ np.asarray(BT601, dtype=np.float32)).astype(np.float32)


def sharpen(image: np.ndarray, amount: float, sigma_px: float = 1.0) -> np.ndarray:
    """Unsharp mask: image + amount * (image - Gaussian(image)); overshoots beside every edge."""
    image = image.astype(np.float32)
    if amount <= 0:
        return image
    blurred = cv2.GaussianBlur(image, (0, 0), sigma_px, borderType=cv2.BORDER_REPLICATE)
    return image + amount * (image - blurred)


def to_u8(image_dn: np.ndarray) -> np.ndarray:
    """Whole DN in [0, 255]."""
    return np.clip(np.rint(image_dn), 0, 255).astype(np.uint8)


# ---------------------------------------------------------------------------------------------
# 4. JPEG


def jpeg_roundtrip(luma: np.ndarray, quality: int) -> np.ndarray:
    """The luma after JPEG at `quality` (OpenCV's libjpeg; a grey JPEG is a colour one's Y plane)."""
    ok, data = cv2.imencode(".jpg", luma, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError("JPEG encoding failed")
    return cv2.imdecode(data, cv2.IMREAD_GRAYSCALE)


# ---------------------------------------------------------------------------------------------
# the chain


def develop(
    signal_dn: np.ndarray,
    chain: ChainSpec,
    *,
    electrons_per_dn: float,
    read_noise_dn: float,
    black_level_dn: float,
    halo_sigma_px: float,
    rng: np.random.Generator,
    saturation_dn: float = 255.0,
) -> np.ndarray:
    """The luma (uint8) a phone makes of the noiseless light `signal_dn` (H, W) or (H, W, 3).

    `signal_dn` is the renderer's, on the sensor's own pixels (twice the frame's size when the
    chain bins), with each panel's defocus already applied. `electrons_per_dn` and
    `read_noise_dn` are at the chosen ISO; `halo_sigma_px` is the halo's width on this grid.
    """
    optics, pixels, isp = chain.optics, chain.pixels, chain.isp
    light = veiling_glare(signal_dn, optics.glare_fraction)
    light = halo(light, optics.halo_fraction, halo_sigma_px)
    binned = pixels.binning == 2
    raw = bayer_mosaic(light, quad=binned) if pixels.bayer else luma_bt601(light)
    electrons = full_well(shot_noise(to_electrons(raw, electrons_per_dn, black_level_dn), rng), pixels.full_well_e)
    dn = read_out(electrons, electrons_per_dn, read_noise_dn, black_level_dn, saturation_dn, rng)
    if binned:
        dn = bin2x2(dn)
    codes = quantize_raw(dn, pixels.raw_bits, saturation_dn)
    if pixels.bayer:
        image = demosaic(codes, pixels.raw_bits, saturation_dn, isp.demosaic)
    else:
        image = codes.astype(np.float32) * (saturation_dn / ((1 << pixels.raw_bits) - 1))
    image = reduce_noise(image, isp.noise_reduction, isp.noise_sigma_px, isp.noise_sigma_dn)
    image = apply_tone_curve(image, isp.tone_curve, saturation_dn, isp.s_curve_contrast)
    luma = sharpen(luma_bt601(image), isp.sharpen_amount, isp.sharpen_sigma_px)
    frame = to_u8(luma * (255.0 / saturation_dn))
    if chain.jpeg_quality is not None:
        frame = jpeg_roundtrip(frame, chain.jpeg_quality)
    return frame
