"""Sampling: a scene's series expanded into camera poses, and rendered into fixture files.

A series is one of: explicit poses, the paper's FOV grid (eqs. 1-7) under a beacon, any
rectangular grid, or a walk (zig-zag, converging square spiral, waypoints at a speed and
frame rate; `simulator.trajectories`). Rotation variation (fixed attitude, random tilt and yaw,
smooth hand shake) is drawn per sample from the scene's seed, so a series is the same on any
machine and with any number of workers.

Output folder: NAME_0000.y + NAME_0000.json ... (the contract's fixtures, with ground truth and
a `simulator` block naming the scene and sample), `scene.json` (the exact scene) and
`map.json` (its beacon map, for `lumipose locate --map`).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from server.fov import fov_grid, grid_points
from server.geometry import rotation_from_ypr
from shared_schemas import FrameMeta, device_profiles
from shared_schemas.api import cell_label
from simulator import trajectories
from simulator.bursts import burst_scenes, burst_span_s, capture_starts, render_burst
from simulator.fixtures import write_fixture
from simulator.render import CameraPose
from simulator.scene import (
    FovGridSeries, GridSeries, PosesSeries, RotationSpec, Scene, SeriesSpec, TrajectorySeries, readout_motion,
    render_sample,
)


@dataclass(frozen=True)
class SamplePose:
    index: int
    t_s: float
    position_m: tuple[float, float, float]
    ypr_deg: tuple[float, float, float]
    label: str = ""  # e.g. the grid cell "-8,11" (shared_schemas.api.cell_label)
    velocity_mps: tuple[float, float, float] = (0.0, 0.0, 0.0)  # during readout, map frame
    angular_velocity_dps: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def camera_pose(self, t_s: float | None = None) -> CameraPose:
        """The camera at `t_s` (default: the sample's own time), moved on at the sample's velocities."""
        dt = 0.0 if t_s is None else t_s - self.t_s
        turn, _ = cv2.Rodrigues(np.radians(self.angular_velocity_dps) * dt)  # map frame, as ReadoutMotion
        return CameraPose(np.add(self.position_m, np.multiply(self.velocity_mps, dt)),
                          turn @ rotation_from_ypr(*self.ypr_deg))


def sample_rng(seed: int, index: int, stream: int) -> np.random.Generator:
    """The generator of one sample's `stream` (0 attitude, 1 rendering): the same in any process."""
    return np.random.default_rng([seed, index, stream])


def fov_grid_positions(scene: Scene, series: FovGridSeries) -> tuple[np.ndarray, np.ndarray]:
    """(labels (N, 2), positions (N, 3)) of the paper's grid under the chosen beacon."""
    beacon = next(b for b in scene.beacons if series.beacon_id in (None, b.id))
    distance_m = beacon.center_m[2] - series.height_m
    if distance_m <= 0:
        raise ValueError(f"series.path.height_m {series.height_m} is not below beacon {beacon.id}")
    camera = scene.camera
    if camera.profile is None:
        raise ValueError("a fov_grid series needs a camera with a device profile (paper eq. 2: R * P)")
    profile = device_profiles()[camera.profile]
    updates = {k: getattr(camera, k) for k in ("pixel_size_m", "focal_length_m") if getattr(camera, k) is not None}
    grid = fov_grid(profile.model_copy(update=updates), distance_m, series.cell_m, beacon.size_m)
    labels, offsets = grid_points(grid)
    positions = np.column_stack([offsets + beacon.center_m[:2], np.full(len(offsets), series.height_m)])
    return labels, positions


def _path_positions(scene: Scene, path) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(times (N,), positions (N, 3), labels) of a series' path, before any rotation."""
    if isinstance(path, PosesSeries):
        positions = np.array([p.position_m for p in path.poses], dtype=float)
        return np.array([p.t_s for p in path.poses]), positions, [""] * len(positions)
    if isinstance(path, FovGridSeries):
        labels, positions = fov_grid_positions(scene, path)
        return np.zeros(len(positions)), positions, [cell_label(i, j) for i, j in labels]
    if isinstance(path, GridSeries):
        xs = np.arange(path.x_m[0], path.x_m[1] + path.x_m[2] * 1e-6, path.x_m[2])
        ys = np.arange(path.y_m[1], path.y_m[0] - path.y_m[2] * 1e-6, -path.y_m[2])  # top row first, as the paper
        positions = np.array([(x, y, path.height_m) for y in ys for x in xs])
        # cell labels counted from the grid's centre, as the paper labels its bench
        centre = [(path.x_m[0] + xs[-1]) / 2, (path.y_m[0] + ys[0]) / 2]
        labels = [cell_label(round((x - centre[0]) / path.x_m[2]), round((y - centre[1]) / path.y_m[2]))
                  for x, y, _ in positions]
        return np.zeros(len(positions)), positions, labels
    if isinstance(path, TrajectorySeries):
        if path.kind == "waypoints":
            walk = trajectories.waypoints(np.array(path.points_m), path.speed_mps, path.frame_interval_s, path.height_m)
        else:
            make = trajectories.zigzag if path.kind == "zigzag" else trajectories.square_spiral
            walk = make(trajectories.Area(*path.area_m), path.spacing_m, path.speed_mps, path.frame_interval_s,
                        path.height_m)
        return np.array([w.t_s for w in walk]), np.array([w.position_m for w in walk]), [""] * len(walk)
    raise TypeError(f"unknown series path {type(path).__name__}")


def _attitudes(rotation: RotationSpec, times_s: np.ndarray, positions: np.ndarray, seed: int,
               fixed_ypr: np.ndarray | None) -> np.ndarray:
    """(N, 3) yaw, pitch, roll in degrees for each sample."""
    count = len(times_s)
    ypr = np.tile([rotation.yaw_deg, rotation.pitch_deg, rotation.roll_deg], (count, 1)).astype(float)
    if fixed_ypr is not None:
        ypr += fixed_ypr
    if rotation.face_walking_direction and count > 1:
        walk = [trajectories.TimedPosition(t, p) for t, p in zip(times_s, positions)]
        ypr[:, 0] += trajectories.walking_yaw_deg(walk)
    for index in range(count):
        rng = sample_rng(seed, index, 0)
        tilt = rng.uniform(0.0, rotation.max_tilt_deg)
        azimuth = rng.uniform(0.0, 2 * math.pi)
        yaw = rng.uniform(-rotation.yaw_jitter_deg, rotation.yaw_jitter_deg)
        ypr[index] += [yaw, tilt * math.cos(azimuth), tilt * math.sin(azimuth)]
    if rotation.shake_deg > 0:
        ypr += trajectories.hand_shake_deg(times_s, rotation.shake_deg, seed)
    return ypr


def world_rate_dps(ypr_deg: np.ndarray, ypr_rate_dps: np.ndarray) -> np.ndarray:
    """Angular velocity (N, 3) in the map frame of R = Rz(yaw) Ry(pitch) Rx(roll) changing at `ypr_rate_dps`."""
    rates = []
    for (yaw, pitch, _), (d_yaw, d_pitch, d_roll) in zip(ypr_deg, ypr_rate_dps):
        yaw_axis = np.array([0.0, 0.0, 1.0])
        pitch_axis = rotation_from_ypr(yaw, 0.0, 0.0)[:, 1]
        roll_axis = rotation_from_ypr(yaw, pitch, 0.0)[:, 0]
        rates.append(d_yaw * yaw_axis + d_pitch * pitch_axis + d_roll * roll_axis)
    return np.array(rates).reshape(-1, 3)


def _velocities(times: np.ndarray, positions: np.ndarray, ypr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear (m/s) and angular (deg/s) velocity at each sample of a timed path; zero if untimed."""
    if len(times) < 2 or np.any(np.diff(times) <= 0):
        return np.zeros_like(positions), np.zeros_like(ypr)
    return np.gradient(positions, times, axis=0), world_rate_dps(ypr, np.gradient(ypr, times, axis=0))


def series_poses(scene: Scene, series: SeriesSpec | None = None) -> list[SamplePose]:
    """The camera poses of `series` (default: the scene's own), deterministic for the scene's seed.

    A walk's samples carry its velocity (and the hand shake's turn rate), which the rolling
    shutter turns into a skewed image; explicit poses carry their own.
    """
    series = series or scene.series
    if series is None:
        raise ValueError("the scene has no series: give one (series.path) or a single pose")
    times, positions, labels = _path_positions(scene, series.path)
    explicit = isinstance(series.path, PosesSeries)
    fixed = np.array([p.ypr_deg for p in series.path.poses], dtype=float) if explicit else None
    ypr = _attitudes(series.rotation, times, positions, scene.seed, fixed)
    if explicit:
        velocity = np.array([p.velocity_mps for p in series.path.poses], dtype=float)
        spin = np.array([p.angular_velocity_dps for p in series.path.poses], dtype=float)
    elif isinstance(series.path, TrajectorySeries):
        velocity, spin = _velocities(times, positions, ypr)
    else:
        velocity, spin = np.zeros_like(positions), np.zeros_like(positions)
    return [SamplePose(i, float(t), tuple(map(float, p)), tuple(map(float, a)), label, tuple(map(float, v)),
                       tuple(map(float, w)))
            for i, (t, p, a, label, v, w) in enumerate(zip(times, positions, ypr, labels, velocity, spin))]


def render_pose(scene: Scene, sample: SamplePose) -> tuple[np.ndarray, object]:
    """(pixels, FrameMeta) of one sample; its noise depends only on the scene's seed and the index."""
    motion = readout_motion(scene, sample.velocity_mps, sample.angular_velocity_dps)
    return render_sample(scene, sample.camera_pose(), sample_rng(scene.seed, sample.index, 1), sample.t_s, motion,
                         simulator=_simulator_block(scene, sample))


def _simulator_block(scene: Scene, sample: SamplePose) -> dict:
    """The fixture's `simulator` block: how to render the sample again."""
    return {"scene": "scene.json", "sample": sample.index, "seed": scene.seed, "t_s": sample.t_s,
            "ypr_deg": list(sample.ypr_deg), "label": sample.label, "velocity_mps": list(sample.velocity_mps),
            "angular_velocity_dps": list(sample.angular_velocity_dps)}


def progress(done: int, total: int, label: str, stream=None) -> None:
    """A one-line progress bar on a terminal; every tenth on a log. `stream` defaults to sys.stderr as it is
    now (read at each call: a default bound at import would keep a stream replaced and closed since)."""
    stream = stream or sys.stderr
    if stream.isatty():
        filled = int(30 * done / max(total, 1))
        print(f"\r{label} [{'#' * filled}{'.' * (30 - filled)}] {done}/{total}", end="\n" if done == total else "",
              file=stream, flush=True)
    elif done == total or done % max(1, total // 10) == 0:
        print(f"{label}: {done}/{total}", file=stream, flush=True)


def parallel_map(function: Callable, items: list, workers: int | None, label: str) -> Iterator:
    """`function` over `items` in order, on `workers` processes (1 = in this process), with progress."""
    workers = max(1, workers or os.cpu_count() or 1)
    if workers == 1 or len(items) <= 1:
        results: Iterable = map(function, items)
        pool = None
    else:
        pool = ProcessPoolExecutor(max_workers=workers)
        results = pool.map(function, items, chunksize=1)
    try:
        for done, result in enumerate(results, start=1):
            progress(done, len(items), label)
            yield result
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)


def _write_one(args: tuple[Scene, SamplePose, Path]) -> str:
    scene, sample, out_dir = args
    pixels, meta = render_pose(scene, sample)
    raw, _ = write_fixture(out_dir / f"{scene.name}_{sample.index:04d}", pixels, meta)
    return raw.stem


def render_capture(scene: Scene, sample: SamplePose, start_s: float) -> list[tuple[np.ndarray, FrameMeta]]:
    """One capture of the sample (`simulator.bursts`) starting at `start_s`, as `simulate --bursts` writes it."""
    return render_burst(
        burst_scenes(scene), start_s, lambda t: sample.camera_pose(sample.t_s + t - start_s),
        sample_rng(scene.seed, sample.index, 1),
        motion_of=lambda frame_scene: readout_motion(frame_scene, sample.velocity_mps, sample.angular_velocity_dps),
        simulator=_simulator_block(scene, sample))


def _write_burst(args: tuple[Scene, SamplePose, Path, float]) -> list[str]:
    """One capture of the sample (`simulator.bursts`) starting at `start_s`: NAME_0000_0_pose, NAME_0000_1_id, ..."""
    scene, sample, out_dir, start_s = args
    frames = render_capture(scene, sample, start_s)
    stems = []
    for k, (pixels, meta) in enumerate(frames):
        raw, _ = write_fixture(out_dir / f"{scene.name}_{sample.index:04d}_{k}_{meta.frame_kind.value}", pixels, meta)
        stems.append(raw.stem)
    return stems


def write_series(scene: Scene, out_dir: Path, workers: int | None = None, bursts: bool = False) -> list[str]:
    """Render the scene's series into `out_dir` as fixtures, with scene.json and map.json.

    With `bursts` each sample is a capture: its pose frame and ID frames (`simulator.bursts`),
    named so that sorting by name gives capture order; captures that would overlap in time (an
    untimed series, a walk faster than a burst) start when the previous one has ended.
    Returns the fixtures' stems. scene.json is the scene exactly as rendered (series and seed
    included), so `lumipose simulate out/scene.json` makes the same files again.
    """
    samples = series_poses(scene)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "scene.json").write_text(scene.to_json())
    (out_dir / "map.json").write_text(scene.beacon_map().model_dump_json(by_alias=True, indent=2) + "\n")
    label = f"simulate {scene.name}"
    if bursts:
        starts = capture_starts([sample.t_s for sample in samples], burst_span_s(scene))
        captures = [(scene, sample, out_dir, start) for sample, start in zip(samples, starts)]
        return [stem for stems in parallel_map(_write_burst, captures, workers, label) for stem in stems]
    jobs = [(scene, sample, out_dir) for sample in samples]
    return list(parallel_map(_write_one, jobs, workers, label))
