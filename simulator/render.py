"""A small exact renderer: a rounded-square panel through a pinhole camera.

Coverage is the area of each pixel inside the projected outline, exact along x and a
midpoint rule over `subrows` scanlines per pixel row along y; then the Gaussian PSF acts on
the unclipped light, then shot and read noise, clipping and quantisation (the contract's
"Physics": the clipped edge's mid level lies outside the true edge).

Scenes go through `render_emitters`: any number of bright polygons (panels, a window, a lamp,
a reflection), each with its own level, extra blur and per-row gain (rolling shutter), then
vignetting, noise and clipping over the whole frame. Lens distortion acts through the
projection of the densified outlines (`world_polygon_px`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from scipy.special import ndtr

from server.geometry import (
    beacon_to_world,
    camera_matrix,
    distortion_vector,
    beacon_outline_m,
    dense_beacon_outline_m,
    world_to_camera,
)
from shared_schemas import Beacon, CameraIntrinsics
from simulator.chain import defocus


@dataclass(frozen=True)
class SensorModel:
    background_dn: float = 8.0  # ambient light + black level
    plateau_dn: float = 1000.0  # the panel's unclipped level; > saturation means overexposed
    psf_sigma_px: float = 1.0
    electrons_per_dn: float = 16.0  # shot noise variance in DN^2 = signal / electrons_per_dn
    read_noise_dn: float = 1.5
    saturation_dn: float = 255.0
    vignetting: float = 0.0  # share of the light lost at the image corner, falling off as r^2
    # sub-pixels per pixel side for the PSF: a Gaussian sampled at whole pixels is not the
    # continuous PSF (a clipped edge lands ~0.1 px off at sigma 1); None = enough for sigma * s >= 2.5
    psf_supersample: int | None = None

    def supersample_for(self, sigma_px: float) -> int:
        if self.psf_supersample is not None:
            return max(1, int(self.psf_supersample))
        return 1 if sigma_px <= 0 else int(np.clip(np.ceil(2.5 / sigma_px), 1, 4))


@dataclass(frozen=True)
class Emitter:
    """One bright polygon of a frame, already in the frame's pixels."""

    outline_px: np.ndarray  # (N, 2) closed polygon
    level_dn: float  # unclipped level where the polygon covers a whole pixel
    row_gain: np.ndarray | None = None  # (height,) multiplier per sensor row, rolling shutter
    extra_blur_px: float = 0.0  # on top of the PSF: a reflection or a diffuser is soft
    defocus_px: float = 0.0  # diameter of the defocus disc (`simulator.chain.pillbox_kernel`), after the PSF
    # a moving camera: the outline at instants spread over each row's exposure; the light is their mean (motion blur)
    exposure_outlines_px: tuple[np.ndarray, ...] = ()


@dataclass(frozen=True)
class CameraPose:
    position_m: np.ndarray  # (3,) optical centre, map frame
    rotation_wc: np.ndarray  # (3, 3) camera to world


def beacon_outline_px(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, max_step_px: float = 0.5) -> np.ndarray:
    """Closed outline (N, 2) of the panel in the frame's pixels, points <= ~max_step_px apart
    (the straight sides too, so that distortion bends them)."""
    coarse = beacon_outline_m(beacon, 16)
    in_camera = world_to_camera(beacon_to_world(beacon, coarse), pose.position_m, pose.rotation_wc)
    if np.any(in_camera[:, 2] <= 0):
        raise ValueError("the beacon is not entirely in front of the camera")
    span_px = camera.fx * beacon.size_m / in_camera[:, 2].min()
    dense = dense_beacon_outline_m(beacon, span_px, max_step_px)
    in_camera = world_to_camera(beacon_to_world(beacon, dense), pose.position_m, pose.rotation_wc)
    pixels, _ = cv2.projectPoints(in_camera, np.zeros(3), np.zeros(3), camera_matrix(camera),
                                  distortion_vector(camera))
    return pixels.reshape(-1, 2)


NEAR_PLANE_M = 1e-3


@dataclass(frozen=True)
class ReadoutMotion:
    """The camera moving while a rolling shutter reads the frame out.

    Row r integrates light over [r * row_time_s, r * row_time_s + exposure_s] after the frame's
    timestamp (the first row's exposure start); it is seen from the pose at `instant` of that
    window (0.5: its middle), the pose at the timestamp moved by `velocity_mps` and turned by
    `angular_velocity_dps` (both in the map frame). The blur within the window is the mean over
    instants (`exposure_polygons_px`).
    """

    velocity_mps: np.ndarray  # (3,)
    angular_velocity_dps: np.ndarray  # (3,)
    row_time_s: float
    exposure_s: float
    instant: float = 0.5  # share of each row's exposure window

    def time_of_row(self, rows):
        """Seconds after the timestamp at which row(s) `rows` are seen."""
        return rows * self.row_time_s + self.exposure_s * self.instant

    def to_camera(self, points_m: np.ndarray, pose: CameraPose, rows: np.ndarray) -> np.ndarray:
        """Map-frame points (N, 3) in the camera frame of the rows (N,) they are seen on."""
        tau = self.time_of_row(rows)[:, None]
        relative = points_m - np.asarray(pose.position_m) - tau * np.asarray(self.velocity_mps)
        omega = np.radians(np.asarray(self.angular_velocity_dps, dtype=float))
        rate = float(np.linalg.norm(omega))
        if rate > 0:  # undo the turn R(tau) = Rot(omega tau) R0 (Rodrigues, angle -rate * tau)
            axis = omega / rate
            angle = -rate * tau
            relative = (relative * np.cos(angle) + np.cross(axis, relative) * np.sin(angle)
                        + axis * (relative @ axis)[:, None] * (1 - np.cos(angle)))
        return relative @ np.asarray(pose.rotation_wc)


def _clip_near(points_c: np.ndarray) -> np.ndarray:
    """The closed polygon (N, 3) in camera coordinates cut to z >= NEAR_PLANE_M (Sutherland-Hodgman)."""
    kept = []
    for a, b in zip(points_c, np.roll(points_c, -1, axis=0)):
        a_in, b_in = a[2] >= NEAR_PLANE_M, b[2] >= NEAR_PLANE_M
        if a_in:
            kept.append(a)
        if a_in != b_in:
            t = (NEAR_PLANE_M - a[2]) / (b[2] - a[2])
            kept.append(a + t * (b - a))
    return np.array(kept).reshape(-1, 3)


def world_polygon_px(points_m: np.ndarray, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                     max_step_px: float = 1.0, motion: ReadoutMotion | None = None) -> np.ndarray | None:
    """Closed polygon (N, 3) of the map frame in the frame's (distorted) pixels, or None if unseen.

    Parts behind the camera are cut off. Polygons whose pinhole image misses the frame enlarged
    by half its size are None: far off-axis the distortion polynomial folds points back in.
    Sides are densified to <= ~max_step_px so that distortion bends them. With `motion` each
    point is seen from the pose of the row it lands on (found by fixed-point iteration).
    """
    in_camera = _clip_near(world_to_camera(np.asarray(points_m, dtype=float), pose.position_m, pose.rotation_wc))
    if len(in_camera) < 3:
        return None
    matrix = camera_matrix(camera)
    pinhole = in_camera[:, :2] / in_camera[:, 2:] * [camera.fx, camera.fy] + [camera.cx, camera.cy]
    if (pinhole[:, 0].max() < -width / 2 or pinhole[:, 0].min() > 1.5 * width
            or pinhole[:, 1].max() < -height / 2 or pinhole[:, 1].min() > 1.5 * height):
        return None
    closed = np.vstack([in_camera, in_camera[:1]])
    ends = np.vstack([pinhole, pinhole[:1]])
    lengths_px = np.linalg.norm(np.diff(ends, axis=0), axis=1)
    pieces = [a + np.linspace(0.0, 1.0, max(1, int(np.ceil(n / max_step_px))), endpoint=False)[:, None] * (b - a)
              for a, b, n in zip(closed[:-1], closed[1:], np.minimum(lengths_px, 4.0 * (width + height)))]
    dense = np.concatenate(pieces)
    pixels, _ = cv2.projectPoints(dense, np.zeros(3), np.zeros(3), matrix, distortion_vector(camera))
    pixels = pixels.reshape(-1, 2)
    if motion is not None:
        dense_m = dense @ np.asarray(pose.rotation_wc).T + np.asarray(pose.position_m)
        for _ in range(4):  # a row moves the point by far less than a row per iteration
            rows = np.clip(pixels[:, 1], 0, height - 1)
            moved = motion.to_camera(dense_m, pose, rows)
            moved[:, 2] = np.maximum(moved[:, 2], NEAR_PLANE_M)
            pixels, _ = cv2.projectPoints(moved, np.zeros(3), np.zeros(3), matrix, distortion_vector(camera))
            pixels = pixels.reshape(-1, 2)
    return pixels


BLUR_STEP_PX = 0.25  # the most the image moves between two instants of a row's exposure
MAX_INSTANTS = 256  # a bound on the cost of a fast turn; the step is then coarser


def exposure_polygons_px(points_m: np.ndarray, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                         max_step_px: float = 1.0, motion: ReadoutMotion | None = None,
                         step_px: float = BLUR_STEP_PX) -> tuple[np.ndarray, tuple[np.ndarray, ...]] | None:
    """(the polygon as `world_polygon_px` sees it, the polygon at n instants spread over each row's
    exposure) or None if unseen; `Emitter` draws the mean light of the instants (motion blur).

    The instants are (k + 0.5) / n of the window, n such that the image moves <= `step_px` from one
    to the next; none (an empty tuple) when the camera stands still or moves less than `step_px`
    during the exposure, so that such frames are drawn exactly as without blur.
    """
    seen = world_polygon_px(points_m, camera, pose, width, height, max_step_px, motion)
    if seen is None or motion is None:
        return None if seen is None else (seen, ())

    def at(instant: float) -> np.ndarray:
        return world_polygon_px(points_m, camera, pose, width, height, max_step_px, replace(motion, instant=instant))

    start, end = at(0.0), at(1.0)  # the same points: the same densifying
    travel_px = float(np.max(np.linalg.norm(end - start, axis=1)[_near_frame(start, end, width, height)]))
    instants = min(MAX_INSTANTS, int(np.ceil(travel_px / step_px)))
    if instants <= 1:
        return seen, ()
    return seen, tuple(at((k + 0.5) / instants) for k in range(instants))


def _near_frame(start_px: np.ndarray, end_px: np.ndarray, width: int, height: int) -> np.ndarray:
    """Which points stay within the frame enlarged by half its size over the exposure (all of them
    when none does). A polygon cut at the near plane (a wall beside the camera) has points projected
    far out whose travel would ask for the most instants while only the part in the frame is drawn."""
    low, high = np.minimum(start_px, end_px), np.maximum(start_px, end_px)
    near = ((low[:, 0] > -width / 2) & (high[:, 0] < 1.5 * width)
            & (low[:, 1] > -height / 2) & (high[:, 1] < 1.5 * height))
    return near if near.any() else np.ones(len(near), dtype=bool)


def coverage_map(outline_px: np.ndarray | Sequence[np.ndarray], width: int, height: int,
                 subrows: int = 16) -> np.ndarray:
    """Share (height, width) float32 of each pixel's area inside the closed polygon (or the mean over
    several closed polygons of the same orientation, e.g. one moving during the exposure).

    Pixel (j, i) covers [j - 0.5, j + 0.5) x [i - 0.5, i + 0.5). Each edge crossing a
    scanline at x adds sign * G(x, j), G = clip(j + 0.5 - x, 0, 1) the coverage of pixel j by
    [x, inf); summed with a difference array and a cumulative sum along the row.
    """
    outlines = [outline_px] if isinstance(outline_px, np.ndarray) else list(outline_px)
    start = np.concatenate(outlines)
    end = np.concatenate([np.roll(outline, -1, axis=0) for outline in outlines])
    y_min = max(-0.5, float(start[:, 1].min()))
    y_max = min(height - 0.5, float(start[:, 1].max()))
    coverage = np.zeros((height, width), np.float32)
    if y_max <= y_min:
        return coverage
    first = int(np.floor((y_min + 0.5) * subrows))
    last = int(np.ceil((y_max + 0.5) * subrows))
    scan_y = (np.arange(first, last) + 0.5) / subrows - 0.5
    # crossings: edge k crosses scanline y when min(y0, y1) <= y < max(y0, y1) (half-open)
    low = np.minimum(start[:, 1], end[:, 1])
    high = np.maximum(start[:, 1], end[:, 1])
    lo_idx = np.searchsorted(scan_y, low, side="left")
    hi_idx = np.searchsorted(scan_y, high, side="left")
    counts = hi_idx - lo_idx
    edges = np.repeat(np.arange(len(start)), counts)
    rows = np.concatenate([np.arange(a, b) for a, b in zip(lo_idx, hi_idx) if b > a]) if counts.sum() else np.array([], int)
    y = scan_y[rows]
    x0, y0, x1, y1 = start[edges, 0], start[edges, 1], end[edges, 0], end[edges, 1]
    x = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    sign = np.where(y1 > y0, 1.0, -1.0)
    pixel_row = np.floor(y + 0.5).astype(np.int64)
    x = np.clip(x, -0.5, width - 0.5 - 1e-6)  # keeps k + 1 inside the row
    k = np.floor(x + 0.5).astype(np.int64)
    inside = k + 0.5 - x  # G(x, k)
    cols = width + 1
    flat = np.concatenate([pixel_row * cols + k, pixel_row * cols + k + 1])
    weights = np.concatenate([sign * inside, sign * (1.0 - inside)]) / subrows
    if len(outlines) > 1:
        weights /= len(outlines)
    difference = np.bincount(flat, weights=weights, minlength=height * cols).reshape(height, cols)
    accumulated = np.cumsum(difference[:, :width], axis=1)
    return np.abs(accumulated).astype(np.float32)


def exact_polygon_area_px(outline_px: np.ndarray) -> float:
    x, y = outline_px[:, 0], outline_px[:, 1]
    return 0.5 * abs(float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))


def vignetting_map(width: int, height: int, vignetting: float) -> np.ndarray:
    """Relative illumination (height, width) float32: 1 at the centre, 1 - vignetting at the corners."""
    x = (np.arange(width, dtype=np.float32) - (width - 1) / 2) / ((width - 1) / 2 or 1)
    y = (np.arange(height, dtype=np.float32) - (height - 1) / 2) / ((height - 1) / 2 or 1)
    return 1.0 - vignetting * (y[:, None] ** 2 + x[None, :] ** 2) / 2.0


def _check_row_gain(row_gain: np.ndarray | None, height: int) -> np.ndarray | None:
    if row_gain is None:
        return None
    row_gain = np.asarray(row_gain, dtype=np.float32)
    if row_gain.shape != (height,) or not np.all(np.isfinite(row_gain)) or np.any(row_gain < 0):
        raise ValueError(f"row_gain must be {height} finite non-negative values, one per row; got shape {row_gain.shape}")
    return row_gain


def _blurred_coverage(outline_px: list[np.ndarray], width: int, height: int, sigma_px: float, factor: int,
                      defocus_px: float = 0.0) -> np.ndarray:
    """Pixel-area coverage of the polygon (the mean over the polygons) after a Gaussian PSF of `sigma_px`.

    The optical image is the polygon convolved with the PSF, and each pixel integrates it over
    its area. On a grid `factor` times finer the sampled Gaussian is close to the continuous
    one; summing factor x factor sub-pixels then integrates over the pixel. A defocus disc of
    `defocus_px` follows the PSF on the same grid (its kernel's own sub-pixel area adds a variance
    of 1 / (12 factor^2) px^2).
    """
    if sigma_px <= 0:
        return defocus(coverage_map(outline_px, width, height), defocus_px)
    if factor == 1:
        return defocus(cv2.GaussianBlur(coverage_map(outline_px, width, height), (0, 0), sigma_px,
                                        borderType=cv2.BORDER_REPLICATE), defocus_px)
    fine = coverage_map([(outline + 0.5) * factor - 0.5 for outline in outline_px], width * factor, height * factor,
                        subrows=max(4, 16 // factor))
    fine = cv2.GaussianBlur(fine, (0, 0), sigma_px * factor, borderType=cv2.BORDER_REPLICATE)
    fine = defocus(fine, defocus_px * factor)
    return fine.reshape(height, factor, width, factor).mean(axis=(1, 3))


def _noisy_u8(signal: np.ndarray, sensor: SensorModel, rng: np.random.Generator) -> np.ndarray:
    """Shot and read noise, rounding to whole DN and clipping to the 8-bit range."""
    sigma_dn = np.sqrt(signal / sensor.electrons_per_dn + sensor.read_noise_dn**2)
    noisy = signal + sigma_dn * rng.standard_normal(signal.shape, dtype=np.float32)
    return np.clip(np.rint(noisy), 0, sensor.saturation_dn).astype(np.uint8)


def _background_u8(shape: tuple[int, int], sensor: SensorModel, rng: np.random.Generator) -> np.ndarray:
    """`_noisy_u8` of a flat background, drawn from its 256-level distribution (4x faster).

    The rounded, clipped normal is sampled by inverse CDF from 16-bit uniforms: each level's
    probability is right to 2^-16.
    """
    sigma = math.sqrt(sensor.background_dn / sensor.electrons_per_dn + sensor.read_noise_dn**2)
    levels = np.arange(int(sensor.saturation_dn) + 1)
    if sigma == 0:
        cdf = (levels + 0.5 > sensor.background_dn).astype(float)
    else:
        cdf = ndtr((levels + 0.5 - sensor.background_dn) / sigma)
    cdf[-1] = 1.0
    table = np.searchsorted(cdf, (np.arange(65536) + 0.5) / 65536, side="right").astype(np.uint8)
    return table[rng.integers(0, 65536, shape, dtype=np.uint16)]


def _emitter_boxes(emitters: list[Emitter], width: int, height: int,
                   sensor: SensorModel) -> list[tuple[int, int, int, int, np.ndarray]]:
    """Each emitter's light (y0, y1, x0, x1, light) on its bounding box: coverage blurred by the
    PSF (and its own extra blur) and its defocus disc, then scaled per row by its `row_gain`."""
    boxes = []
    for emitter in emitters:
        row_gain = _check_row_gain(emitter.row_gain, height)
        outlines = list(emitter.exposure_outlines_px) or [emitter.outline_px]
        outline = np.concatenate(outlines)
        sigma = float(np.hypot(sensor.psf_sigma_px, emitter.extra_blur_px))
        margin = int(np.ceil(5 * sigma)) + 2 + int(np.ceil(emitter.defocus_px / 2))
        x0 = max(0, int(np.floor(outline[:, 0].min())) - margin)
        y0 = max(0, int(np.floor(outline[:, 1].min())) - margin)
        x1 = min(width, int(np.ceil(outline[:, 0].max())) + margin + 1)
        y1 = min(height, int(np.ceil(outline[:, 1].max())) + margin + 1)
        if x1 <= x0 or y1 <= y0:
            continue
        # the box is cut at the frame's border: blurring replicates the border, as light beyond it would
        light = emitter.level_dn * _blurred_coverage([o - [x0, y0] for o in outlines], x1 - x0, y1 - y0, sigma,
                                                     sensor.supersample_for(sigma), emitter.defocus_px)
        if row_gain is not None:
            light *= row_gain[y0:y1, None]
        boxes.append((y0, y1, x0, x1, light))
    return boxes


def render_signal(emitters: list[Emitter], width: int, height: int, sensor: SensorModel) -> np.ndarray:
    """The noiseless light (height, width) float32 DN, unclipped: background, every emitter, vignetting.

    What `render_emitters` adds its noise to; the phone chain (`simulator.chain.develop`) starts here.
    """
    signal = np.full((height, width), sensor.background_dn, np.float32)
    for y0, y1, x0, x1, light in _emitter_boxes(emitters, width, height, sensor):
        signal[y0:y1, x0:x1] += light
    if sensor.vignetting:
        signal *= vignetting_map(width, height, sensor.vignetting)
    return signal


def render_emitters(emitters: list[Emitter], width: int, height: int, sensor: SensorModel,
                    rng: np.random.Generator) -> np.ndarray:
    """An 8-bit luma frame (height, width): background plus every emitter, PSF, vignetting, noise.

    Each emitter's coverage is blurred by the PSF (and its own extra blur) on its own bounding
    box, scaled per row by its `row_gain` (the rolling shutter: light reaches a row only
    during that row's exposure window, after the optics) and added to the background.
    Without vignetting the flat background outside the emitters' boxes takes a faster path
    with the same noise statistics.
    """
    if sensor.vignetting:
        return _noisy_u8(render_signal(emitters, width, height, sensor), sensor, rng)
    boxes = _emitter_boxes(emitters, width, height, sensor)
    frame = _background_u8((height, width), sensor, rng)
    if boxes:
        # the union of the boxes gets the exact treatment (boxes may overlap)
        top, bottom = min(b[0] for b in boxes), max(b[1] for b in boxes)
        left, right = min(b[2] for b in boxes), max(b[3] for b in boxes)
        signal = np.full((bottom - top, right - left), sensor.background_dn, np.float32)
        for y0, y1, x0, x1, light in boxes:
            signal[y0 - top:y1 - top, x0 - left:x1 - left] += light
        frame[top:bottom, left:right] = _noisy_u8(signal, sensor, rng)
    return frame


def render_frame(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                 sensor: SensorModel, rng: np.random.Generator, row_gain: np.ndarray | None = None) -> np.ndarray:
    """An 8-bit luma frame (height, width) of the panel seen from `pose`.

    `row_gain` (height,) multiplies the panel's light per sensor row (a rolling shutter
    integrating the LED waveform over each row's exposure window, see `simulator.led`); it acts
    after the optical PSF, which happens before the sensor, and before noise and clipping.
    """
    _check_row_gain(row_gain, height)
    outline = beacon_outline_px(beacon, camera, pose)
    return render_emitters([Emitter(outline, sensor.plateau_dn, row_gain)], width, height, sensor, rng)
