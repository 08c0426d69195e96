"""`lumipose bench grid` and `lumipose bench bench-real`: the paper's Tables 1-2, Figs. 11-14.

grid: the simulated test bench of Section IV-B. Xiaomi Mi 8 front camera at full resolution
facing a 0.174 m panel (0.02 m corner radius) 1 m above, at the 391 corners of the paper's FOV
grid (eqs. 1-7, 0.05 m cells), no tilt (face to face). The scene is `simulator/scenes/
paper-bench.json`: 10 ms at ISO 100, the panel four times over saturation, PSF sigma 1 px.

bench-real: the same grid as the paper's real bench of Section IV-C saw it. What changes, and
why (each is a knob of the scene; the defaults are in `RealBench`):
- the real lens is 5 % longer than the datasheet's 3.52 mm, so the field of view is narrower
  than the grid that eqs. 1-7 drew from the datasheet: the panel is partly outside the image
  in the outer columns and rows, as in the paper's Fig. 14;
- radial lens distortion (a few pixels at the image edges), a wider PSF (2 px), ISO 400 noise,
  vignetting;
- the phone sits in its box with some play: a fixed 0.4 degree pitch and up to 0.5 degree of
  random tilt and 1 degree of yaw per placement.
The pipeline is told the true (calibrated) intrinsics, or with `calibrated=False` the
datasheet's pinhole without distortion, as the paper's pipeline assumed.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from server.camera import intrinsics_from_profile
from server.pipeline import PipelineOptions
from shared_schemas import DeviceProfile, device_profiles
from simulator import reports
from simulator.sampling import series_poses
from simulator.scene import GridSeries, RotationSpec, Scene, SeriesSpec, find_scene

PAPER_TABLE_1 = {"mean_mm": 7.49, "std_mm": 1.32, "min_mm": 5.07, "max_mm": 15.82, "coverage_pct": 100.0}
PAPER_TABLE_2 = {"mean_mm": 20.44, "std_mm": 13.65, "min_mm": 0.28, "max_mm": 49.79, "coverage_pct": 79.03}


@dataclass(frozen=True)
class RealBench:
    focal_scale: float = 1.05
    distortion: tuple[float, ...] = (0.004, -0.003, 0.0, 0.0, 0.0)
    psf_sigma_px: float = 2.0
    iso: float = 400.0
    exposure_s: float = 0.001
    vignetting: float = 0.3
    pitch_deg: float = 0.4
    max_tilt_deg: float = 0.5
    yaw_jitter_deg: float = 1.0
    calibrated: bool = True


def grid_scene(scale: float = 1.0, seed: int | None = None, yaw_jitter_deg: float = 0.0) -> Scene:
    """The paper's simulated bench (scene file `paper-bench`), at `scale` of full resolution.

    `yaw_jitter_deg` turns the phone by a random yaw within +-jitter at each point: exactly
    face to face (0, the paper's setup) every side of the panel runs along the pixel grid.
    """
    scene = find_scene("paper-bench")
    updates = {"camera": scene.camera.model_copy(update={"scale": scale})}
    if seed is not None:
        updates["seed"] = seed
    if yaw_jitter_deg:
        updates["series"] = scene.series.model_copy(update={"rotation": RotationSpec(yaw_jitter_deg=yaw_jitter_deg)})
    return Scene.model_validate(scene.model_copy(update=updates).model_dump(by_alias=True))


def real_bench_scene(bench: RealBench = RealBench(), scale: float = 1.0, seed: int | None = None) -> Scene:
    """The bench as the real phone saw it; the grid is still the datasheet's (explicit x, y)."""
    scene = grid_scene(scale, seed)
    nominal = reports_grid_extent(scene)
    profile = device_profiles()[scene.camera.profile]
    camera = scene.camera.model_copy(update={"focal_length_m": profile.focal_length_m * bench.focal_scale,
                                             "distortion": list(bench.distortion)})
    sensor = scene.sensor.model_copy(update={"psf_sigma_px": bench.psf_sigma_px, "iso": bench.iso,
                                             "exposure_s": bench.exposure_s, "vignetting": bench.vignetting})
    rotation = RotationSpec(pitch_deg=bench.pitch_deg, max_tilt_deg=bench.max_tilt_deg,
                            yaw_jitter_deg=bench.yaw_jitter_deg)
    series = SeriesSpec(path=GridSeries(x_m=[-nominal[0], nominal[0], 0.05], y_m=[-nominal[1], nominal[1], 0.05]),
                        rotation=rotation)
    return Scene.model_validate({**scene.model_dump(by_alias=True), "name": "paper-bench-real",
                                 "camera": camera.model_dump(), "sensor": sensor.model_dump(),
                                 "series": series.model_dump()})


def reports_grid_extent(scene: Scene) -> tuple[float, float]:
    """Half width and half height (m) of the scene's own FOV grid (its series must be a fov_grid)."""
    positions = [p.position_m for p in series_poses(scene)]
    xs, ys = [p[0] for p in positions], [p[1] for p in positions]
    return (max(xs) - min(xs)) / 2, (max(ys) - min(ys)) / 2


def run_grid_bench(scene: Scene, figures_dir: Path | None, title: str, workers: int | None = None,
                   pipeline_camera=None, limit: int | None = None) -> dict:
    """Locate every sample of the scene's series (or about `limit` of them, evenly spread); the table, and
    with `figures_dir` the figures plus the data they were drawn from (scene.json, outcomes.json) there."""
    planned = series_poses(scene)
    samples = planned if limit is None else planned[::max(1, len(planned) // limit)][:limit]
    jobs = [reports.LocateJob(scene, sample, PipelineOptions(), pipeline_camera) for sample in samples]
    start = time.perf_counter()
    outcomes = reports.locate_series(jobs, workers, title)
    wall_s = time.perf_counter() - start
    report = {"title": title, "scene": scene.name, "summary": reports.table(outcomes),
              "failures": reports.failures(outcomes), "wall_s": wall_s, "workers": workers or os.cpu_count()}
    if figures_dir is not None:
        report["figures"] = [str(f) for f in write_grid_figures(scene, outcomes, Path(figures_dir), title, planned)]
    return report


def write_grid_figures(scene: Scene, outcomes: list[reports.Outcome], figures_dir: Path, title: str,
                       planned: list) -> list[Path]:
    """Scatter (and for a grid, the heat map over the whole planned grid) with scene.json and outcomes.json."""
    figures_dir.mkdir(parents=True, exist_ok=True)
    (figures_dir / "scene.json").write_text(scene.to_json())
    reports.write_outcomes(outcomes, figures_dir / "outcomes.json")
    figures = [figures_dir / f"{scene.name}-scatter.png"]
    reports.plot_scatter(outcomes, figures[0], title)
    path = scene.series.path
    if path.kind in ("fov_grid", "grid"):  # a walk's positions make no heat map
        cell_m = path.cell_m if path.kind == "fov_grid" else path.x_m[2]
        figures.append(figures_dir / f"{scene.name}-heatmap.png")
        reports.plot_heatmap(outcomes, figures[1], title, cell_m, np.array([p.position_m[:2] for p in planned]))
    return figures


def bench_grid(figures_dir: Path | None, scale: float = 1.0, seed: int | None = None, workers: int | None = None,
               limit: int | None = None, scene_name: str | None = None, yaw_jitter_deg: float = 0.0) -> dict:
    """The paper's grid, or the series of any scene file (`scene_name`) at its own resolution."""
    if scene_name is None:
        scene = grid_scene(scale, seed, yaw_jitter_deg)
        title = "simulated grid, 1 m, Mi 8 front" + (f", yaw +-{yaw_jitter_deg:g} deg" if yaw_jitter_deg else "")
    else:
        scene = find_scene(scene_name)
        if seed is not None:
            scene = scene.model_copy(update={"seed": seed})
        title = f"scene {scene.name}"
    report = run_grid_bench(scene, figures_dir, title, workers, limit=limit)
    if scene_name is None:
        report["paper"] = PAPER_TABLE_1
    return report


def bench_real(figures_dir: Path | None, bench: RealBench = RealBench(), scale: float = 1.0, seed: int | None = None,
               workers: int | None = None, limit: int | None = None, profile: DeviceProfile | None = None) -> dict:
    """The real-like bench located with the true lens, the datasheet pinhole (`bench.calibrated` False) or a
    calibrated `profile` (scaled and cropped to the bench's frames as any frame naming it)."""
    scene = real_bench_scene(bench, scale, seed)
    pipeline_camera = None
    if profile is not None:
        pipeline_camera = intrinsics_from_profile(profile, *scene.camera.frame_size())
        title = f"real-like bench, 1 m, calibrated profile {profile.id}"
    elif not bench.calibrated:
        pipeline_camera = intrinsics_from_profile(device_profiles()[scene.camera.profile], *scene.camera.frame_size())
        title = "real-like bench, 1 m, datasheet pinhole"
    else:
        title = "real-like bench, 1 m, true lens"
    report = run_grid_bench(scene, figures_dir, title, workers, pipeline_camera, limit)
    report["paper"] = PAPER_TABLE_2
    report["bench"] = bench.__dict__
    if profile is not None:
        report["profile"] = profile.model_dump(mode="json")
    return report
