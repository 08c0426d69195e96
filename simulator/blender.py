"""A second, independent renderer: Blender's Cycles path tracer (the paper's simulator engine).

Optional: needs `bpy` (`pip install -e ".[blender]"`; Blender 4.2 LTS runs on Python 3.11).
It renders the same rounded panel as `simulator.render` from the same pose, as an emissive
mesh seen by a Blender camera with the same sensor and focal length, and returns the linear
radiance (1.0 = the panel's full level) of the pixels around the panel only (a render border:
the rest of the frame is black and would cost most of the time). Used by
`lumipose bench fidelity --blender` (the paper's Fig. 10 between two renderers) and, through
`render_blender_frame` (the same sensor as `simulator.render.render_frame`), by
`lumipose bench accuracy --renderer blender`.

Conventions: Blender cameras look along their local -Z with +Y up in the image; an OpenCV
camera looks along +Z with y down, so R_blender = R_wc diag(1, -1, -1). Blender puts the
principal point at the image centre, which is the profiles' (w - 1) / 2, (h - 1) / 2 in
OpenCV's pixel-centre coordinates; distortion is not rendered (Cycles' perspective camera has
no OpenCV model), so a camera with distortion or an off-centre principal point is refused.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from server.geometry import beacon_outline_m, beacon_to_world
from shared_schemas import Beacon, CameraIntrinsics
from simulator.chain import ChainSpec, defocus
from simulator.render import CameraPose, SensorModel, _noisy_u8, beacon_outline_px, vignetting_map
from simulator.scene import defocus_px, develop_signal


@dataclass(frozen=True)
class BlenderSettings:
    samples: int = 32  # per pixel; emission only, so this only smooths the pixel filter
    # Cycles' pixel filter: the radiance is point-sampled through it (no pixel area on top). Its Gaussian of width w
    # has sigma w / 4 (CYCLES_GAUSSIAN_SIGMA_PER_WIDTH): 0.75 px at 3 px, which `bench fidelity --blender` keeps;
    # Blackman-Harris 1.5 (Cycles' default) is so sharp that a 50 % reading interpolated between pixels depends on the
    # edge's sub-pixel phase (0.1 px at 3 m). `render_blender_frame` sets the sensor's own (`sensor_pixel_filter`).
    filter_width_px: float = 3.0
    pixel_filter: str = "GAUSSIAN"  # Cycles' pixel_filter_type: BOX, GAUSSIAN or BLACKMAN_HARRIS
    adaptive_sampling: bool = True  # Cycles' default
    adaptive_threshold: float = 0.01  # Cycles' default
    adaptive_min_samples: int = 0  # 0 = Cycles' choice
    margin_px: int = 12
    threads: int = 0  # 0 = Blender's choice (all cores)


@dataclass(frozen=True)
class BlenderCrop:
    radiance: np.ndarray  # (h, w) float64, linear, 1.0 = the panel's level
    origin_px: tuple[int, int]  # (x0, y0) of radiance[0, 0] in the full frame


def _bpy():
    try:
        import bpy
    except ImportError as error:  # pragma: no cover - depends on the environment
        raise RuntimeError("the Blender renderer needs bpy: pip install -e '.[blender]' (Blender 4.2 LTS, "
                           "Python 3.11)") from error
    return bpy


def _check_camera(camera: CameraIntrinsics, width: int, height: int) -> None:
    if any(camera.distortion):
        raise ValueError("camera.distortion: the Blender renderer draws an ideal pinhole only")
    if abs(camera.cx - (width - 1) / 2) > 1e-6 or abs(camera.cy - (height - 1) / 2) > 1e-6:
        raise ValueError("camera.cx, camera.cy: the Blender renderer needs the principal point at the centre")
    if abs(camera.fx - camera.fy) > 1e-9 * camera.fx:
        raise ValueError("camera.fy: the Blender renderer needs square pixels (fx == fy)")


def render_blender(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                   settings: BlenderSettings = BlenderSettings()) -> BlenderCrop:
    """Linear radiance around the panel as Cycles renders it (the panel must be inside the frame)."""
    _check_camera(camera, width, height)
    bpy = _bpy()
    import bmesh
    from mathutils import Matrix

    outline_px = beacon_outline_px(beacon, camera, pose)  # only to place the render border
    # the pixel filter reaches +-1.5 width (Gaussian), +-width (Blackman-Harris) or +-width / 2 (box)
    margin = max(settings.margin_px, int(math.ceil(1.5 * settings.filter_width_px)) + 2)
    x0 = max(0, int(math.floor(outline_px[:, 0].min())) - margin)
    y0 = max(0, int(math.floor(outline_px[:, 1].min())) - margin)
    x1 = min(width, int(math.ceil(outline_px[:, 0].max())) + margin + 1)
    y1 = min(height, int(math.ceil(outline_px[:, 1].max())) + margin + 1)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = settings.samples
    scene.cycles.use_denoising = False
    scene.cycles.pixel_filter_type = settings.pixel_filter
    scene.cycles.use_adaptive_sampling = settings.adaptive_sampling
    scene.cycles.adaptive_threshold = settings.adaptive_threshold
    scene.cycles.adaptive_min_samples = settings.adaptive_min_samples
    scene.cycles.filter_width = settings.filter_width_px
    if settings.threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = settings.threads
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Raw"  # linear values in the file
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_depth = "16"
    scene.render.image_settings.color_mode = "BW"
    scene.world = bpy.data.worlds.new("black")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs[1].default_value = 0.0

    lens = bpy.data.cameras.new("phone")
    lens.sensor_fit = "HORIZONTAL"
    lens.sensor_width = 36.0
    lens.lens = 36.0 * camera.fx / width  # the same fx in pixels, whatever the physical sizes
    camera_object = bpy.data.objects.new("phone", lens)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    rotation = np.asarray(pose.rotation_wc) @ np.diag([1.0, -1.0, -1.0])
    world = np.eye(4)
    world[:3, :3], world[:3, 3] = rotation, pose.position_m
    camera_object.matrix_world = Matrix(world.tolist())

    points = beacon_to_world(beacon, beacon_outline_m(beacon, 64))
    mesh = bpy.data.meshes.new("panel")
    builder = bmesh.new()
    builder.faces.new([builder.verts.new(tuple(p)) for p in points])
    builder.to_mesh(mesh)
    builder.free()
    material = bpy.data.materials.new("emission")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs[1].default_value = 1.0
    output = nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(emission.outputs[0], output.inputs[0])
    mesh.materials.append(material)
    scene.collection.objects.link(bpy.data.objects.new("panel", mesh))

    # border in Blender's normalised coordinates, origin at the bottom left; a quarter pixel past
    # each whole-pixel bound, so that rounding and truncation both land on it
    scene.render.use_border = True
    scene.render.use_crop_to_border = True
    scene.render.border_min_x, scene.render.border_max_x = (x0 + 0.25) / width, (x1 + 0.25) / width
    scene.render.border_min_y = (height - y1 + 0.25) / height
    scene.render.border_max_y = (height - y0 + 0.25) / height
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "panel.png"
        scene.render.filepath = str(path)
        with open(os.devnull, "w") as quiet, _redirect_stdout(quiet):
            bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(str(path))
        image.colorspace_settings.name = "Non-Color"  # the file holds linear values (view "Raw")
        size_x, size_y = image.size
        radiance = np.array(image.pixels[:], dtype=float).reshape(size_y, size_x, -1)[::-1, :, 0]
    if radiance.shape != (y1 - y0, x1 - x0):
        raise RuntimeError(f"Blender returned a {radiance.shape} crop, expected {(y1 - y0, x1 - x0)}")
    return BlenderCrop(radiance, (x0, y0))


CYCLES_GAUSSIAN_SIGMA_PER_WIDTH = 0.25  # Cycles triples a Gaussian filter's width and draws exp(-2 (6 v / 3w)^2):
# sigma = width / 4, cut at +-1.5 width (+-6 sigma); Blackman-Harris doubles it (sigma 0.42 px at its default 1.5 px)


def sensor_pixel_filter(sensor: SensorModel, settings: BlenderSettings = BlenderSettings()) -> BlenderSettings:
    """`settings` with Cycles' pixel filter set to the sensor's pixel response: the pixel's area (a 1 px box)
    convolved with the lens PSF (a Gaussian of `sensor.psf_sigma_px`), as `simulator.render` draws it.

    Cycles point-samples the image through its pixel filter, so the filter is the whole response. With no PSF
    it is the box itself; else a Gaussian of the box's and the PSF's variances, sigma^2 + 1/12, which puts a
    clipped edge within 0.001 px of the box-then-Gaussian response for sigma >= 0.8 px (its excess kurtosis,
    -1.2 / (12 sigma^2 + 1)^2, is what differs). The filter's Monte Carlo noise is not smoothed by anything
    afterwards, hence `FRAME_SETTINGS`' samples."""
    if sensor.psf_sigma_px <= 0:
        return replace(settings, pixel_filter="BOX", filter_width_px=1.0)
    sigma = math.sqrt(sensor.psf_sigma_px**2 + 1.0 / 12.0)
    return replace(settings, pixel_filter="GAUSSIAN", filter_width_px=sigma / CYCLES_GAUSSIAN_SIGMA_PER_WIDTH)


# rms 0.0014 of the panel's level on edge pixels at the levels a clipped edge is read at (sigma 1; 0.00085 at 2048
# samples, 0.0006 at 4096): 1.4 DN at a 4x plateau beside the sensor's 3.2 DN. About 1.5 min a full-resolution frame
FRAME_SETTINGS = BlenderSettings(samples=1024, adaptive_threshold=0.001)


def render_blender_frame(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                         sensor: SensorModel, rng: np.random.Generator,
                         settings: BlenderSettings = FRAME_SETTINGS) -> np.ndarray:
    """An 8-bit luma frame (height, width) from Cycles' radiance through the sensor of
    `simulator.render.render_frame`: Cycles integrates the panel over each pixel's area blurred by
    the lens PSF (its pixel filter, `sensor_pixel_filter`), at the panel's level over the
    background, vignetting, then shot and read noise, rounding and clipping (the same noise
    model, `render._noisy_u8`)."""
    return _noisy_u8(_blender_signal(beacon, camera, pose, width, height, sensor, settings), sensor, rng)


def render_blender_chain_frame(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                               sensor: SensorModel, chain: ChainSpec, black_level_dn: float, rng: np.random.Generator,
                               settings: BlenderSettings | None = None) -> np.ndarray:
    """The luma frame (height, width) `chain`'s phone makes of Cycles' noiseless light (`render_blender_frame`'s,
    before its noise): the panel defocused by the thin lens's disc for its depth, as `simulator.render` draws
    it, then `simulator.chain.develop`. A still camera on the frame's own pixels: motion during the exposure
    and 2x2 binning are drawn by `simulator.render` only, and refused here. `settings`: FRAME_SETTINGS."""
    if not chain.motion.still:
        raise ValueError("chain.motion: the Blender renderer draws a still camera only")
    if chain.pixels.binning != 1:
        raise ValueError("chain.pixels.binning: the Blender renderer draws the frame's own pixels only")
    signal = _blender_signal(beacon, camera, pose, width, height, sensor, settings or FRAME_SETTINGS)
    signal = defocus(signal, defocus_px(chain, camera, pose, beacon.center_m))
    return develop_signal(chain, signal, camera, sensor, black_level_dn, rng)


def _blender_signal(beacon: Beacon, camera: CameraIntrinsics, pose: CameraPose, width: int, height: int,
                    sensor: SensorModel, settings: BlenderSettings) -> np.ndarray:
    """The noiseless light (DN, float32) of the frame: Cycles' panel at the sensor's level over its background,
    through the sensor's pixel response (`sensor_pixel_filter`), vignetted."""
    crop = render_blender(beacon, camera, pose, width, height, sensor_pixel_filter(sensor, settings))
    light = crop.radiance.astype(np.float32)
    x0, y0 = crop.origin_px
    signal = np.full((height, width), sensor.background_dn, np.float32)
    signal[y0 : y0 + light.shape[0], x0 : x0 + light.shape[1]] += sensor.plateau_dn * light
    if sensor.vignetting:
        signal *= vignetting_map(width, height, sensor.vignetting)
    return signal


class _redirect_stdout:
    """Blender prints a line per tile on the C-level stdout; send it elsewhere for the render."""

    def __init__(self, stream):
        self.stream = stream

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        os.dup2(self.stream.fileno(), 1)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)
