"""Walking paths sampled at a frame rate (the paper's Figs. 17-18), and hand shake.

Pure functions, no rendering. Positions are metres in the map frame (X east, Y north, Z up);
times are seconds from the start of the walk. A path is walked at constant speed along its
polyline and sampled every `frame_interval_s` (the paper took a photo every 0.5 s, the phone
held at about 1.32 m).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


class Area(NamedTuple):
    """An axis-aligned rectangle of the floor plan, metres."""

    x_min_m: float
    y_min_m: float
    x_max_m: float
    y_max_m: float


class TimedPosition(NamedTuple):
    t_s: float
    position_m: np.ndarray  # (3,)


def _check_area(area: Area) -> Area:
    area = Area(*map(float, area))
    if not (area.x_max_m > area.x_min_m and area.y_max_m > area.y_min_m):
        raise ValueError(f"area must have x_max > x_min and y_max > y_min, got {tuple(area)}")
    return area


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive number, got {value}")


def zigzag_vertices(area: Area, spacing_m: float) -> np.ndarray:
    """Corners (N, 2) of a boustrophedon over `area`: legs along X, `spacing_m` apart in Y.

    Starts at (x_min, y_min); the last leg lies on y_max even when the spacing does not divide
    the height (so the whole area is walked).
    """
    area = _check_area(area)
    _check_positive(spacing_m=spacing_m)
    legs = max(1, math.ceil((area.y_max_m - area.y_min_m) / spacing_m - 1e-9))
    ys = np.linspace(area.y_min_m, area.y_max_m, legs + 1)
    vertices = []
    for k, y in enumerate(ys):
        xs = (area.x_min_m, area.x_max_m) if k % 2 == 0 else (area.x_max_m, area.x_min_m)
        vertices += [(xs[0], y), (xs[1], y)]
    return np.array(vertices)


def square_spiral_vertices(area: Area, spacing_m: float) -> np.ndarray:
    """Corners (N, 2) of a converging square spiral: along the border, then inwards.

    Starts at (x_min, y_min) going east and turns counter-clockwise; after each full ring the
    path steps `spacing_m` inwards, until the next ring would be empty.
    """
    area = _check_area(area)
    _check_positive(spacing_m=spacing_m)
    left, bottom, right, top = area
    vertices = [(left, bottom)]

    def walk_to(point: tuple[float, float]) -> bool:
        if np.hypot(point[0] - vertices[-1][0], point[1] - vertices[-1][1]) < 1e-9:
            return False
        vertices.append(point)
        return True

    while True:
        legs = [(right, bottom), (right, top), (left, top), (left, min(bottom + spacing_m, top))]
        if not all(walk_to(leg) for leg in legs):
            break
        left, bottom, right, top = left + spacing_m, bottom + spacing_m, right - spacing_m, top - spacing_m
        if right < left - 1e-9 or top < bottom - 1e-9:
            break
        walk_to((left, bottom))
        if right - left < 1e-9 or top - bottom < 1e-9:  # the last ring is a line: walk it
            walk_to((right, top))
            break
    return np.array(vertices)


def waypoints(points_m: np.ndarray, speed_mps: float, frame_interval_s: float,
              height_m: float | None = None) -> list[TimedPosition]:
    """Walk the polyline `points_m` (N, 2 or 3) at `speed_mps`, one position per frame.

    Frames at t = 0, dt, 2 dt, ... up to the end of the path (the end itself is included
    when it falls on a frame). 2D points get z = `height_m` (required for them).
    """
    points = np.asarray(points_m, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) < 1:
        raise ValueError(f"points_m must be (N, 2) or (N, 3) with N >= 1, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise ValueError("points_m must be finite")
    _check_positive(speed_mps=speed_mps, frame_interval_s=frame_interval_s)
    if points.shape[1] == 2:
        if height_m is None:
            raise ValueError("height_m is required for 2D waypoints")
        points = np.column_stack([points, np.full(len(points), float(height_m))])
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    along = np.concatenate([[0.0], np.cumsum(lengths)])
    duration_s = along[-1] / speed_mps
    count = int(math.floor(duration_s / frame_interval_s + 1e-9)) + 1
    times = np.arange(count) * frame_interval_s
    distance = np.minimum(times * speed_mps, along[-1])
    positions = np.column_stack([np.interp(distance, along, points[:, k]) for k in range(3)])
    return [TimedPosition(float(t), p) for t, p in zip(times, positions)]


def zigzag(area: Area, spacing_m: float, speed_mps: float, frame_interval_s: float,
           height_m: float = 1.32) -> list[TimedPosition]:
    """The zig-zag walk of Fig. 17 over `area`, phone at `height_m`."""
    return waypoints(zigzag_vertices(area, spacing_m), speed_mps, frame_interval_s, height_m)


def square_spiral(area: Area, spacing_m: float, speed_mps: float, frame_interval_s: float,
                  height_m: float = 1.32) -> list[TimedPosition]:
    """The converging square spiral of Fig. 18 over `area`, phone at `height_m`."""
    return waypoints(square_spiral_vertices(area, spacing_m), speed_mps, frame_interval_s, height_m)


def walking_yaw_deg(path: list[TimedPosition]) -> np.ndarray:
    """Yaw (N,) of the walking direction, degrees about +Z from +X; the last step's at the end."""
    positions = np.array([p.position_m for p in path])
    if len(positions) < 2:
        return np.zeros(len(positions))
    steps = np.diff(positions[:, :2], axis=0)
    yaw = np.degrees(np.arctan2(steps[:, 1], steps[:, 0]))
    return np.concatenate([yaw, yaw[-1:]])


def hand_shake_deg(times_s: np.ndarray, amplitude_deg: float, seed: int,
                   band_hz: tuple[float, float] = (0.5, 3.0), components: int = 4) -> np.ndarray:
    """Smooth random attitude offsets (N, 3) = (yaw, pitch, roll) in degrees at `times_s`.

    Each angle is a sum of `components` sinusoids with frequencies drawn in `band_hz` (the slow
    sway of a hand holding a phone) and random phases, scaled so that its RMS is
    `amplitude_deg`. Deterministic for a seed; continuous in time, so neighbouring frames of a
    walk are correlated as a real hand's are.
    """
    times = np.asarray(times_s, dtype=float)
    if amplitude_deg < 0 or not math.isfinite(amplitude_deg):
        raise ValueError(f"amplitude_deg must be >= 0, got {amplitude_deg}")
    if not (0 < band_hz[0] <= band_hz[1]):
        raise ValueError(f"band_hz must be 0 < low <= high, got {band_hz}")
    rng = np.random.default_rng(seed)
    frequencies = rng.uniform(*band_hz, (3, components))
    phases = rng.uniform(0, 2 * np.pi, (3, components))
    weights = rng.uniform(0.5, 1.0, (3, components))
    waves = weights[None] * np.sin(2 * np.pi * frequencies[None] * times[:, None, None] + phases[None])
    rms = np.sqrt(0.5 * np.sum(weights**2, axis=1))  # RMS of a sum of sines of distinct frequencies
    return amplitude_deg * waves.sum(axis=2) / rms[None]
