"""Photos of a ChArUco board through a known lens, to prove camera calibration (issue 14).

The board is a textured plane: OpenCV's own image of the board (`server.calibration.board`),
one texel grid per square so that every chessboard edge falls exactly on texel edges, on a
white paper margin, in front of a grey background. Each output pixel is mapped back through the
lens: the pixel's `supersample` x `supersample` sample points are undistorted (OpenCV's
iterative undistortion, exactly on a grid every `GRID_STEP_PX` pixels, bilinear in between: the
undistortion bends by far less than 1e-3 px over that step), their rays meet the board plane
(the inverse homography) and sample the texture; the pixel's reflectance is their mean. Then
the optical PSF (a Gaussian), shot and read noise and 8-bit clipping (`simulator.render`).

Poses (`board_poses`) are drawn like a person shooting a calibration set: the board 0.3-0.8 m
away, tilted 10-50 degrees, its centre aimed at cells spread over the whole image (so that some
views reach each corner); and the two poor sets a calibration must refuse: all views frontal,
or the board only in one corner of the image.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from enum import StrEnum

import cv2
import numpy as np

from server.calibration.board import charuco_board
from server.calibration.lens import Lens
from shared_schemas.calibration import BoardSpec
from simulator.render import SensorModel, _noisy_u8

GRID_STEP_PX = 4  # exact undistortion every 4 px; bilinear between (error ~ f'' h^2 / 8 < 1e-3 px)
TEXELS_PER_SQUARE = 120  # markers' bits need only be legible; the chessboard edges are exact at any size
ROWS_PER_CHUNK = 64  # bounds the memory of the supersampled arrays (~100 MB at 4 x 4 on a 3880 px row)


@dataclass(frozen=True)
class BoardPose:
    """Board to camera: a board point X (metres, board frame: x along its width, y down its height,
    z into the board) sits at rotation @ X + translation in the camera frame."""

    rotation: np.ndarray  # (3, 3)
    translation: np.ndarray  # (3,)

    @property
    def tilt_deg(self) -> float:
        return float(np.degrees(np.arccos(np.clip(abs(self.rotation[2, 2]), 0.0, 1.0))))


@dataclass(frozen=True)
class BoardLook:
    """How the photo looks: paper and ink reflectances, light, background, blur, noise."""

    white: float = 0.85
    black: float = 0.06
    background: float = 0.35  # a grey table or wall around the board
    light_dn: float = 220.0  # DN of a perfect white
    margin_squares: float = 0.5  # white paper around the printed squares
    supersample: int = 4
    sensor: SensorModel = SensorModel(background_dn=4.0, psf_sigma_px=1.0, read_noise_dn=1.5)


def _texture(spec: BoardSpec) -> np.ndarray:
    """The board's texture (rows, cols) uint8, TEXELS_PER_SQUARE texels per square, black 0 white 255."""
    return _texture_of(spec.model_dump_json())


@functools.cache  # by the spec's JSON: the models are not hashable
def _texture_of(spec_json: str) -> np.ndarray:
    spec = BoardSpec.model_validate_json(spec_json)
    size = (spec.squares_x * TEXELS_PER_SQUARE, spec.squares_y * TEXELS_PER_SQUARE)
    return charuco_board(spec).generateImage(size, marginSize=0, borderBits=1)


@functools.cache
def _ray_grid(lens: Lens, width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Normalised rays on the grid -0.5, -0.5 + GRID_STEP_PX, ... covering the frame: (xs, ys, ray x, ray y)."""
    xs = np.arange(-0.5, width - 0.5 + GRID_STEP_PX, GRID_STEP_PX)
    ys = np.arange(-0.5, height - 0.5 + GRID_STEP_PX, GRID_STEP_PX)
    grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    rays = lens.rays(grid).reshape(len(ys), len(xs), 2)
    return xs, ys, rays[..., 0], rays[..., 1]


def _interpolator(positions: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Index of the grid node left of each position and the weight of the next (the regular grid of `_ray_grid`)."""
    scaled = (positions + 0.5) / GRID_STEP_PX
    index = np.clip(np.floor(scaled).astype(np.int64), 0, count - 2)
    return index, scaled - index


def _reflectance(spec: BoardSpec, look: BoardLook, lens: Lens, pose: BoardPose, width: int, height: int,
                 box: tuple[int, int, int, int]) -> np.ndarray:
    """Mean reflectance (height, width) float32 of each pixel's sample points."""
    xs, ys, ray_x, ray_y = _ray_grid(lens, width, height)
    texture = _texture(spec)
    margin = look.margin_squares * spec.square_m
    board_w, board_h = spec.squares_x * spec.square_m, spec.squares_y * spec.square_m
    per_m = TEXELS_PER_SQUARE / spec.square_m
    plane = np.column_stack([pose.rotation[:, 0], pose.rotation[:, 1], pose.translation])
    inverse = np.linalg.inv(plane)  # normalised ray (x, y, 1) to board (X, Y, 1) up to scale
    n = look.supersample
    offsets = (np.arange(n) + 0.5) / n - 0.5
    reflectance = np.full((height, width), look.background, np.float32)
    x0, x1, y0, y1 = box
    sub_x = (np.arange(x0, x1)[:, None] + offsets).ravel()
    ix, tx = _interpolator(sub_x, len(xs))
    for top in range(y0, y1, ROWS_PER_CHUNK):
        bottom = min(y1, top + ROWS_PER_CHUNK)
        sub_y = (np.arange(top, bottom)[:, None] + offsets).ravel()
        iy, ty = _interpolator(sub_y, len(ys))
        rays = []
        for grid in (ray_x, ray_y):
            rows = grid[iy] * (1 - ty)[:, None] + grid[iy + 1] * ty[:, None]
            rays.append(rows[:, ix] * (1 - tx) + rows[:, ix + 1] * tx)
        w = inverse[2, 0] * rays[0] + inverse[2, 1] * rays[1] + inverse[2, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            bx = (inverse[0, 0] * rays[0] + inverse[0, 1] * rays[1] + inverse[0, 2]) / w
            by = (inverse[1, 0] * rays[0] + inverse[1, 1] * rays[1] + inverse[1, 2]) / w
        # w > 0: the ray meets the plane in front of the camera (the plane's depth along the ray is 1 / w)
        on_paper = (w > 0) & (bx >= -margin) & (bx < board_w + margin) & (by >= -margin) & (by < board_h + margin)
        col = np.floor(np.where(on_paper, bx, 0.0) * per_m).astype(np.int64)
        row = np.floor(np.where(on_paper, by, 0.0) * per_m).astype(np.int64)
        printed = on_paper & (col >= 0) & (col < texture.shape[1]) & (row >= 0) & (row < texture.shape[0])
        ink = texture[np.clip(row, 0, texture.shape[0] - 1), np.clip(col, 0, texture.shape[1] - 1)] < 128
        value = np.where(on_paper, look.white, look.background).astype(np.float32)
        value[printed & ink] = look.black
        reflectance[top:bottom, x0:x1] = value.reshape(bottom - top, n, x1 - x0, n).mean(axis=(1, 3))
    return reflectance


def _board_box(spec: BoardSpec, look: BoardLook, lens: Lens, pose: BoardPose, width: int,
               height: int) -> tuple[int, int, int, int] | None:
    """Pixel box (x0, x1, y0, y1) holding the paper's image, or None when it misses the frame."""
    margin = look.margin_squares * spec.square_m
    board_w, board_h = spec.squares_x * spec.square_m, spec.squares_y * spec.square_m
    edge = np.linspace(0.0, 1.0, 65)
    outline = np.concatenate([
        np.column_stack([edge * (board_w + 2 * margin), np.zeros_like(edge)]),
        np.column_stack([edge * (board_w + 2 * margin), np.full_like(edge, board_h + 2 * margin)]),
        np.column_stack([np.zeros_like(edge), edge * (board_h + 2 * margin)]),
        np.column_stack([np.full_like(edge, board_w + 2 * margin), edge * (board_h + 2 * margin)]),
    ]) - margin
    points_c = np.column_stack([outline, np.zeros(len(outline))]) @ pose.rotation.T + pose.translation
    if np.any(points_c[:, 2] <= 0.01):
        raise ValueError("the board is not entirely in front of the camera")
    pixels = lens.project(points_c)
    x0, y0 = np.floor(pixels.min(axis=0)).astype(int) - 2
    x1, y1 = np.ceil(pixels.max(axis=0)).astype(int) + 3
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(width, x1), min(height, y1)
    return None if x1 <= x0 or y1 <= y0 else (int(x0), int(x1), int(y0), int(y1))


def render_board(spec: BoardSpec, lens: Lens, pose: BoardPose, width: int, height: int, rng: np.random.Generator,
                 look: BoardLook = BoardLook()) -> np.ndarray:
    """An 8-bit grey photo (height, width) of the board at `pose` through `lens`."""
    box = _board_box(spec, look, lens, pose, width, height)
    reflectance = (np.full((height, width), look.background, np.float32) if box is None
                   else _reflectance(spec, look, lens, pose, width, height, box))
    signal = look.sensor.background_dn + look.light_dn * reflectance
    if look.sensor.psf_sigma_px > 0:
        signal = cv2.GaussianBlur(signal, (0, 0), look.sensor.psf_sigma_px, borderType=cv2.BORDER_REPLICATE)
    return _noisy_u8(signal, look.sensor, rng)


class PoseSet(StrEnum):
    good = "good"  # 0.3-0.8 m, tilted 10-50 degrees, aimed all over the image
    frontal = "frontal"  # poor: every view nearly face on (tilt < 3 degrees)
    corner = "corner"  # poor: the board only in the top-left corner of the image


@dataclass(frozen=True)
class PoseRules:
    distance_m: tuple[float, float] = (0.3, 0.8)
    tilt_deg: tuple[float, float] = (10.0, 50.0)
    frontal_tilt_deg: float = 3.0
    roll_deg: float = 20.0  # the board turned in its plane
    min_corners_in_frame: float = 0.35  # share of the board's corners a view must show (partial views reach corners)
    # the good set's first views each put a board corner this close (share of the frame's width) to a frame
    # corner, as a careful user does: the distortion is largest, and least certain, there
    corner_views: int = 8
    corner_reach: float = 0.05
    attempts: int = 200


def _rotation(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    return cv2.Rodrigues(np.asarray(axis, float) * angle_rad)[0]


def _aimed_pose(spec: BoardSpec, lens: Lens, target_px: np.ndarray, distance_m: float, tilt_deg: float,
                tilt_axis_rad: float, roll_deg: float) -> BoardPose:
    """The board's centre on the ray of `target_px` at `distance_m`, tilted about an in-plane axis and rolled."""
    roll = _rotation(np.array([0.0, 0.0, 1.0]), np.radians(roll_deg))
    axis = np.array([np.cos(tilt_axis_rad), np.sin(tilt_axis_rad), 0.0])
    rotation = _rotation(axis, np.radians(tilt_deg)) @ roll
    ray = np.append(lens.rays(target_px[None])[0], 1.0)
    centre_c = distance_m * ray / np.linalg.norm(ray)
    centre_b = np.array([spec.squares_x * spec.square_m / 2, spec.squares_y * spec.square_m / 2, 0.0])
    return BoardPose(rotation=rotation, translation=centre_c - rotation @ centre_b)


def corners_in_frame(spec: BoardSpec, lens: Lens, pose: BoardPose, width: int, height: int) -> float:
    """Share of the board's inner corners whose image lies inside the frame (3 px in from its border)."""
    corners = charuco_board(spec).getChessboardCorners()
    points_c = corners @ pose.rotation.T + pose.translation
    if np.any(points_c[:, 2] <= 0.01):
        return 0.0
    pixels = lens.project(points_c)
    inside = (pixels[:, 0] >= 3) & (pixels[:, 0] <= width - 4) & (pixels[:, 1] >= 3) & (pixels[:, 1] <= height - 4)
    return float(inside.mean())


def _reach_px(spec: BoardSpec, lens: Lens, pose: BoardPose, corner_px: np.ndarray, width: int, height: int) -> float:
    """Distance (px) from a frame corner to the nearest board corner imaged inside the frame."""
    points_c = charuco_board(spec).getChessboardCorners() @ pose.rotation.T + pose.translation
    pixels = lens.project(points_c)
    inside = (pixels[:, 0] >= 3) & (pixels[:, 0] <= width - 4) & (pixels[:, 1] >= 3) & (pixels[:, 1] <= height - 4)
    return float(np.linalg.norm(pixels[inside] - corner_px, axis=1).min()) if inside.any() else np.inf


def board_poses(spec: BoardSpec, lens: Lens, width: int, height: int, count: int, rng: np.random.Generator,
                kind: PoseSet = PoseSet.good, rules: PoseRules = PoseRules()) -> list[BoardPose]:
    """`count` poses of the set `kind`; the good set aims the board's centre at stratified cells of the image."""
    frame_corners = np.array([[0, 0], [width, 0], [0, height], [width, height]], float)
    spread = max(0, count - rules.corner_views) if kind is PoseSet.good else count
    cols = max(1, int(round(np.sqrt(max(spread, 1) * width / height))))
    rows = int(np.ceil(max(spread, 1) / cols))
    poses: list[BoardPose] = []
    for k in range(count):
        aim_corner = kind is PoseSet.good and k < rules.corner_views
        cell_index = k - rules.corner_views if kind is PoseSet.good else k
        for _ in range(rules.attempts):
            if kind is PoseSet.corner:  # the centre in the top-left fifth of the image, the board far off
                target = rng.uniform([0.04, 0.04], [0.2, 0.2]) * [width, height]
                distance = rng.uniform(rules.distance_m[1] * 0.9, rules.distance_m[1])
            elif aim_corner:  # the centre near frame corner k mod 4, the board close: one of its corners reaches it
                corner = frame_corners[k % 4]
                target = corner + (rng.uniform(0.05, 0.3, 2) * [width, height]) * np.sign([width, height] - 2 * corner)
                distance = rng.uniform(rules.distance_m[0], np.mean(rules.distance_m))
            else:  # a cell of a cols x rows grid over [-0.05, 1.05] of the image (a centre beyond it reaches the edge)
                cell = np.array([cell_index % cols, (cell_index // cols) % rows], float)
                target = (-0.05 + 1.1 * (cell + rng.uniform(0.2, 0.8, 2)) / [cols, rows]) * [width, height]
                distance = rng.uniform(*rules.distance_m)
            tilt = rng.uniform(0.0, rules.frontal_tilt_deg) if kind is PoseSet.frontal else rng.uniform(*rules.tilt_deg)
            pose = _aimed_pose(spec, lens, target, distance, tilt, rng.uniform(0, 2 * np.pi),
                               rng.uniform(-rules.roll_deg, rules.roll_deg))
            share = corners_in_frame(spec, lens, pose, width, height)
            wanted = 0.9 if kind is PoseSet.corner else rules.min_corners_in_frame
            if share >= wanted and (not aim_corner or _reach_px(spec, lens, pose, frame_corners[k % 4], width,
                                                                height) <= rules.corner_reach * width):
                poses.append(pose)
                break
        else:
            raise ValueError(f"no {kind.value} pose {k} with the board in the frame after {rules.attempts} tries")
    return poses
