"""`lumipose bench distance` and `lumipose bench tilt`: error against distance and tilt.

Both start from the paper's bench scene (Mi 8 front camera, 0.174 m panel, 10 ms, ISO 100).
distance: the panel `d` metres above the camera for d = 1.0, 1.1, ..., 3.0; at each distance a
5 x 5 grid spread over the beacon-adjusted FOV (paper eq. 4, 90 % of it) so that near-edge
views are in every row; face to face.
tilt: at 1 m, the camera tilted by t degrees towards 4 directions (+X, +Y, -X, -Y) at each
point of a 3 x 3 grid of 0.05 m cells under the panel, t = 0, 2.5, ..., 15.
"""

from __future__ import annotations

import math
from pathlib import Path

from server.fov import fov_grid
from shared_schemas import device_profiles
from simulator import reports
from simulator.bench_grid import grid_scene
from simulator.sampling import series_poses
from simulator.scene import GridSeries, PoseSpec, PosesSeries, RotationSpec, Scene, SeriesSpec


def distance_scene(base: Scene, distance_m: float, points_per_side: int = 5, yaw_jitter_deg: float = 0.0) -> Scene:
    """The bench with the panel `distance_m` above the camera and a grid over the FOV (random
    yaw within +-`yaw_jitter_deg`; 0 = exactly face to face)."""
    beacon = base.beacons[0]
    profile = device_profiles()[base.camera.profile]
    extent = fov_grid(profile, distance_m, 0.05, beacon.size_m).beacon_adjusted_m
    half = [0.45 * e for e in extent]
    steps = [2 * h / (points_per_side - 1) for h in half]
    series = SeriesSpec(path=GridSeries(x_m=[-half[0], half[0], steps[0]], y_m=[-half[1], half[1], steps[1]]),
                        rotation=RotationSpec(yaw_jitter_deg=yaw_jitter_deg))
    room = base.room.model_copy(update={"size_m": [4.0, 4.0, distance_m + 0.5], "origin_m": [-2.0, -2.0, 0.0]})
    moved = beacon.model_copy(update={"center_m": [0.0, 0.0, distance_m]})
    return Scene.model_validate({**base.model_dump(by_alias=True), "name": f"distance-{distance_m:.1f}m",
                                 "room": room.model_dump(), "beacons": [moved.model_dump()],
                                 "series": series.model_dump()})


def tilt_scene(base: Scene, tilt_deg: float, cells: int = 1, cell_m: float = 0.05) -> Scene:
    """The 1 m bench with the camera tilted by `tilt_deg` towards +X, +Y, -X and -Y."""
    poses = []
    for j in range(cells, -cells - 1, -1):
        for i in range(-cells, cells + 1):
            for azimuth in (0.0, 90.0, 180.0, 270.0):
                a = math.radians(azimuth)
                # R = Rz(0) Ry(pitch) Rx(roll): pitch turns the optical axis towards +X, roll towards -Y
                poses.append(PoseSpec(position_m=[i * cell_m, j * cell_m, 0.0],
                                      ypr_deg=[0.0, tilt_deg * math.cos(a), -tilt_deg * math.sin(a)]))
    series = SeriesSpec(path=PosesSeries(poses=poses))
    return base.model_copy(update={"name": f"tilt-{tilt_deg:g}deg", "series": series})


def _sweep(scenes: list[tuple[float, Scene]], key: str, workers: int | None) -> list[dict]:
    jobs, spans = [], []
    for value, scene in scenes:
        samples = series_poses(scene)
        spans.append((value, scene, len(jobs), len(jobs) + len(samples)))
        jobs += [reports.LocateJob(scene, sample) for sample in samples]
    outcomes = reports.locate_series(jobs, workers, f"{key} sweep")  # one pool for the whole sweep
    rows = []
    for value, scene, start, stop in spans:
        part = outcomes[start:stop]
        rows.append({key: value, "summary": reports.table(part), "failures": reports.failures(part)})
    return rows


def _sweep_report(rows: list[dict], key: str, figures_dir: Path | None, name: str, title: str, xlabel: str) -> dict:
    report: dict = {"title": f"{name} sweep", "rows": rows}
    if figures_dir is not None:
        Path(figures_dir).mkdir(parents=True, exist_ok=True)
        figure = Path(figures_dir) / f"{name}-sweep.png"
        reports.plot_sweep(rows, key, figure, title, xlabel)
        report["figures"] = [str(figure)]
    return report


def bench_distance(figures_dir: Path | None, distances_m: list[float] | None = None, scale: float = 1.0,
                   seed: int | None = None, workers: int | None = None, yaw_jitter_deg: float = 0.0) -> dict:
    distances_m = distances_m or [round(1.0 + 0.1 * k, 1) for k in range(21)]
    base = grid_scene(scale, seed)
    rows = _sweep([(d, distance_scene(base, d, yaw_jitter_deg=yaw_jitter_deg)) for d in distances_m], "distance_m",
                  workers)
    title = "2D error against distance (5 x 5 grid over the FOV" + (
        f", yaw +-{yaw_jitter_deg:g} deg)" if yaw_jitter_deg else ", face to face)")
    return _sweep_report(rows, "distance_m", figures_dir, "distance", title, "camera to panel distance (m)")


def bench_tilt(figures_dir: Path | None, tilts_deg: list[float] | None = None, scale: float = 1.0,
               seed: int | None = None, workers: int | None = None) -> dict:
    tilts_deg = tilts_deg or [2.5 * k for k in range(7)]
    base = grid_scene(scale, seed)
    rows = _sweep([(t, tilt_scene(base, t)) for t in tilts_deg], "tilt_deg", workers)
    return _sweep_report(rows, "tilt_deg", figures_dir, "tilt",
                         "2D error against tilt (1 m, 3 x 3 points x 4 directions)",
                         "camera tilt (degrees)")


def format_sweep(report: dict, key: str, unit: str) -> str:
    lines = [f"{report['title']}", f"{key:>10} {'mean':>7} {'std':>7} {'min':>7} {'max':>7} {'p95':>7} {'cover':>7}"
             f"  (2D, mm)  refusals"]
    for row in report["rows"]:
        s = row["summary"]
        if "mean_mm" not in s:
            lines.append(f"{row[key]:>9g}{unit} no fix {s['refusals']}")
            continue
        lines.append(f"{row[key]:>9g}{unit} {s['mean_mm']:7.3f} {s['std_mm']:7.3f} {s['min_mm']:7.3f} "
                     f"{s['max_mm']:7.3f} {s['p95_mm']:7.3f} {s['coverage_pct']:6.1f}%  {s['refusals'] or ''}")
    return "\n".join(lines)
