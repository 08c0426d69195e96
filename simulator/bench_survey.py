"""`lumipose bench survey`: a room's panels surveyed from the floor, against the truth (issue 14).

The office (`office`, 4 panels) or the larger office (`office-9`, 9 panels): `frames` hand-held
pose frames from the floor (`simulator.survey`: 1.2-1.6 m, tilts up to 30 degrees, two or more
panels in each, some cut by the border; the scene's sensor, gravity with its 0.1 degree error, a
compass with a 10 degree bias shared by the survey's frames plus 10 degrees of each frame's own,
labels from the true projection), a tape-measure sketch
(every panel but the anchor off by 5 cm in x, y and z and 5 degrees in yaw), and the survey
(`server.survey.run.survey`). Each panel's centre error (mm, 3-D) and yaw error (degrees, modulo
the panel's symmetry) against the truth, beside the sigmas the survey reports; the bearing's
error. Then the office walk (`simulator.bench_office`) positioned once with the surveyed map and
once with the true map: the same captures (same seed), their 2-D errors against the true path.

`run_bearing_bench`: the survey of many seeds, each one the bearing's error against the sigma it
reports (`lumipose bench survey-bearing`): does the sigma hold the errors?
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from server.geometry import wrap_deg
from server.ingest import LumaFrame
from server.survey.chain import symmetry_deg
from server.survey.rules import SurveyRefused
from server.survey.run import SurveyFrame, survey
from shared_schemas import FrameMeta
from simulator.bench_office import OfficeConfig, run_walk
from simulator.scene import find_scene
from simulator.survey import SurveyShots, survey_set, write_survey_fixtures

SCENES = {4: "office", 9: "office-9"}


@dataclass(frozen=True)
class SurveyBenchConfig:
    panels: int = 4
    frames: int = 40
    scale: float | None = None  # of the Mi 8 front camera's resolution; None: the scene's (0.5)
    seed: int = 1
    sketch_error_m: float = 0.05
    sketch_yaw_error_deg: float = 5.0
    walk: str | None = "zigzag"  # None: no walk
    walk_limit: int | None = None  # captures of the walk
    # the panels' luminances spread evenly over +-this share of the scene's (real panels differ by 10-20 %);
    # the same frames otherwise. The walk keeps the scene's panels
    luminance_spread: float = 0.0


def survey_shots(config: SurveyBenchConfig):
    """(scene, true map, sketch, anchor ID, rendered shots) of the bench's office."""
    scene = find_scene(SCENES[config.panels])
    if config.scale is not None:
        scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"scale": config.scale})})
    if config.luminance_spread:
        factors = 1.0 + np.linspace(-config.luminance_spread, config.luminance_spread, len(scene.beacons))
        factors = np.random.default_rng([config.seed, config.panels, 7]).permutation(factors)
        beacons = [
            b.model_copy(update={"luminance_nits": b.luminance_nits * f})
            for b, f in zip(scene.beacons, factors, strict=True)
        ]
        scene = scene.model_copy(update={"beacons": beacons})
    rng = np.random.default_rng([config.seed, config.panels])
    return scene, *survey_set(scene, config.frames, rng, config.sketch_error_m, config.sketch_yaw_error_deg)


def _survey_frames(shots) -> list[SurveyFrame]:
    return [
        SurveyFrame(f"frame_{k:02d}", LumaFrame(s.pixels, FrameMeta.model_validate(s.meta.model_dump(by_alias=True)),
                                                s.meta.camera), s.labels)
        for k, s in enumerate(shots)
    ]


def run_survey_bench(config: SurveyBenchConfig, fixtures: Path | None = None) -> dict:
    """Survey one office and compare with its truth; then its walk with both maps. `fixtures`: a folder
    to write the frames, labels and sketch to (`lumipose survey` reads them)."""
    scene, truth, sketch, anchor, shots = survey_shots(config)
    if fixtures is not None:
        write_survey_fixtures(fixtures / scene.name, shots, sketch)
    frames = _survey_frames(shots)
    start = time.perf_counter()
    report = survey(frames, sketch, anchor, f"{scene.name}-surveyed")
    survey_s = time.perf_counter() - start
    panels = []
    for estimate in report.beacons:
        true = truth.beacon(estimate.beacon_id)
        assert true is not None
        error = 1000 * (np.asarray(estimate.center_m) - np.asarray(true.center_m))
        step = symmetry_deg(true)
        yaw_error = wrap_deg(estimate.yaw_deg - true.yaw_deg)
        yaw_error = float(yaw_error - step * round(yaw_error / step))
        panels.append({
            "beacon_id": estimate.beacon_id, "anchor": estimate.beacon_id == anchor, "frames": estimate.frames,
            "centre_error_mm": float(np.linalg.norm(error)), "centre_error_xyz_mm": error.tolist(),
            "centre_sigma_xyz_mm": [1000 * v for v in estimate.center_sigma_m],
            "yaw_error_deg": yaw_error, "yaw_sigma_deg": estimate.yaw_sigma_deg,
        })
    free = [p for p in panels if not p["anchor"]]
    true_bearing = SurveyShots().true_bearing_deg
    result = {
        "config": asdict(config),
        "scene": scene.name,
        "panel_luminance_nits": {b.id: b.luminance_nits for b in scene.beacons},
        "frames": len(frames),
        "frames_used": report.frames_used,
        "skipped": [s.model_dump() for s in report.skipped],
        "rms_px": report.rms_px,
        "survey_s": survey_s,
        "panels": panels,
        "max_centre_error_mm": max(p["centre_error_mm"] for p in free),
        "max_yaw_error_deg": max(abs(p["yaw_error_deg"]) for p in free),
        "bearing_deg": report.bearing_deg,
        "bearing_sigma_deg": report.bearing_sigma_deg,
        "bearing_error_deg": None if report.bearing_deg is None else wrap_deg(report.bearing_deg - true_bearing),
        "targets": {"centre_mm": 2.0, "yaw_deg": 0.1},
        "map": report.map.model_dump(by_alias=True, exclude_none=True),
    }
    if config.walk is not None:
        office = OfficeConfig(walk=config.walk, scene=scene.name, max_captures=config.walk_limit, seed=config.seed)
        result["walk"] = {
            "walk": config.walk,
            "surveyed_map": run_walk(office, report.map)["summary"],
            "true_map": run_walk(office)["summary"],
        }
    return result


def run_bearing_bench(config: SurveyBenchConfig, seeds: int) -> dict:
    """The bearing's error over its reported sigma on `seeds` surveys (seeds config.seed, +1, ...; no walk):
    a sigma that holds its errors has about 68 / 95 / 99.7 % of them within 1 / 2 / 3 sigma. A seed whose frames
    leave a panel unconnected (the survey refused) is listed under `refused` and left out."""
    true_bearing = SurveyShots().true_bearing_deg
    runs, refused = [], []
    for seed in range(config.seed, config.seed + seeds):
        scene, _, sketch, anchor, shots = survey_shots(replace(config, seed=seed))
        try:
            report = survey(_survey_frames(shots), sketch, anchor, f"{scene.name}-surveyed")
        except SurveyRefused as error:  # a few frames may leave a panel unconnected: no map, no bearing
            refused.append({"seed": seed, "why": error.message})
            continue
        assert report.bearing_deg is not None and report.bearing_sigma_deg is not None
        error = wrap_deg(report.bearing_deg - true_bearing)
        runs.append({"seed": seed, "frames_used": report.frames_used, "bearing_deg": report.bearing_deg,
                     "sigma_deg": report.bearing_sigma_deg, "error_deg": error,
                     "error_over_sigma": error / report.bearing_sigma_deg})
    ratios = np.abs([r["error_over_sigma"] for r in runs])
    return {
        "config": asdict(replace(config, walk=None)),
        "seeds": seeds,
        "compass": {k: v for k, v in asdict(SurveyShots()).items() if k.startswith(("compass", "true_bearing"))},
        "runs": runs,
        "refused": refused,
        "within_sigma_pct": {str(k): float(100 * np.mean(ratios < k)) for k in (1, 2, 3)},
        "rms_error_over_sigma": float(np.sqrt(np.mean(ratios**2))),
        "rms_error_deg": float(np.sqrt(np.mean([r["error_deg"] ** 2 for r in runs]))),
        "mean_sigma_deg": float(np.mean([r["sigma_deg"] for r in runs])),
        "max_abs_error_deg": float(np.max(np.abs([r["error_deg"] for r in runs]))),
    }
