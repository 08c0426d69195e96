"""`lumipose bench accuracy --shape`: the panel-shape table of issue 11, figures, not tests.

The issue's shapes at a 2.7 m ceiling with the phone at 1.3 m, so every panel 1.4 m above the
camera (Xiaomi Mi 8 front camera), beside the paper's 0.174 m square at the same height:

- `square-174`: the paper's panel (0.02 m corners), the reference row; the corner path;
- `square-600`: a 600 x 600 mm panel, 0.01 m corners; the corner path (a square wholly in view);
- `rectangle-1200x300`: a 1200 x 300 mm panel (width along the beacon's x axis), 0.01 m
  corners; the outline fit, its orientation settled by the `yaw_within_90deg` rule;
- `circle-200`: a 0.2 m round downlight; the outline fit, its yaw from the frame's
  `heading_deg`, drawn as the true camera yaw plus a compass error of `heading_sigma_deg`
  (5 degrees, the sigma the fit weighs it with);
- `circle-200-uncapped`: the same frames located with the map's `required_sigma_m` (the outline fit's cap, 10 mm,
  a refusal above it) lifted to 1 m: the compass error alone moves a circle's fix sideways by
  the horizontal distance times the error (5 degrees: 9 mm per 0.1 m), so by default only
  frames taken within about 0.1 m of the point under the downlight get a fix; this row shows
  what the heading gives, and whether the reported ellipse covers it, everywhere in the frame.

Poses are drawn as in `lumipose bench accuracy` (`simulator.benchmarks`): tilt up to
`max_tilt_deg` in a uniformly drawn direction, camera yaw within +-`max_yaw_deg` of the
beacon's (+-40; the rectangle +-80, as its rule holds within 90), PSF and overexposure drawn per
frame, the gravity vector with a `gravity_sigma_deg` error per axis, located with the gravity
prior in the default (auto) mode through `server.locator.locate` and a one-beacon map. Only the
camera's position is drawn differently: the attitude first, then the position so that the
panel's centre lands uniformly over the frame less the panel's shorter size (the beacon-adjusted
field of view), redrawn until the whole outline is inside the frame with `margin_px` to spare.
At full resolution the 1.2 m panel spans ~3350 of the frame's 3880 x 5184 pixels, so across
the frame's width only a few centimetres of position are left; after `position_tries` positions
the attitude is drawn again (counted: this leans the rectangle's yaws away from those that lay
its long side across the frame's width).

Per shape: coverage, mean, std, max and p95 of the 2-D error, mean 3-D error, the share of the
2-D errors inside the fix's reported 95 % ellipse (d^T C_xy^-1 d <= 5.991), the mean reported
2-D sigma (the ellipse's longer semi-axis at one sigma), refusals by reason and the median
time of one `locate` call in the worker.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field

import numpy as np

from server.camera import intrinsics_from_profile
from server.fov import fov_grid
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from server.pose.outline import OutlineFitRules
from shared_schemas import Beacon, BeaconMap, PanelShape, device_profiles
from shared_schemas.cli import BadInput, plural, report_bad_input, table_cell
from simulator.bench_results import frame_outcome
from simulator.benchmarks import noisy_gravity, summarize
from simulator.fixtures import fixture_meta
from simulator.render import CameraPose, SensorModel, beacon_outline_px, render_frame

PROFILE_ID = "xiaomi-mi8-front"
CHI2_2DOF_95 = 5.991  # the 95 % quantile of chi-square with two degrees of freedom
ABOVE_M = 2.7 - 1.3  # the ceiling and phone heights


@dataclass(frozen=True)
class ShapeCase:
    key: str
    label: str
    beacon: Beacon
    max_yaw_deg: float  # camera yaw drawn within this of the beacon's
    heading: bool  # the frame carries heading_deg (the circle's yaw)
    outline_fit: OutlineFitRules = OutlineFitRules()


def shape_cases(above_m: float = ABOVE_M) -> dict[str, ShapeCase]:
    """The benchmark's panels, `above_m` above the camera, by key, in the table's order."""
    centre = [0.0, 0.0, above_m]
    cases = [
        ShapeCase("square-174", "174 mm square (paper)",
                  Beacon(id=0, center_m=centre, side_m=0.174, corner_radius_m=0.02), 40.0, False),
        ShapeCase("square-600", "600 x 600 mm",
                  Beacon(id=0, center_m=centre, side_m=0.6, corner_radius_m=0.01), 40.0, False),
        ShapeCase("rectangle-1200x300", "1200 x 300 mm",
                  Beacon(id=0, center_m=centre, width_m=1.2, height_m=0.3, corner_radius_m=0.01), 80.0, False),
        ShapeCase("circle-200", "200 mm circle + heading",
                  Beacon(id=0, center_m=centre, shape=PanelShape.circle, diameter_m=0.2), 40.0, True),
        ShapeCase("circle-200-uncapped", "  the same, sigma uncapped",
                  Beacon(id=0, center_m=centre, shape=PanelShape.circle, diameter_m=0.2), 40.0, True,
                  OutlineFitRules(max_sigma_m=1.0)),
    ]  # fmt: skip
    return {case.key: case for case in cases}


SHAPES = tuple(shape_cases())


@dataclass(frozen=True)
class ShapesConfig:
    frames: int = 100  # per shape
    scale: float = 1.0  # of the profile's native resolution
    above_m: float = ABOVE_M
    max_tilt_deg: float = 10.0
    psf_sigma_px: tuple[float, float] = (0.8, 1.5)  # as `simulator.benchmarks.AccuracyConfig`
    overexposure: tuple[float, float] = (2.0, 6.0)  # plateau / saturation
    gravity_sigma_deg: float = 0.1
    heading_sigma_deg: float = 5.0  # the circle's compass error, as the outline fit weighs it
    margin_px: float = 8.0
    position_tries: int = 100
    seed: int = 1
    shapes: tuple[str, ...] = field(default=SHAPES)


def draw_shape_pose(
    config: ShapesConfig, case: ShapeCase, camera, width: int, height: int, rng: np.random.Generator
) -> tuple[CameraPose, int]:
    """A pose whose frame holds the whole panel with `margin_px` to spare; and how many
    attitudes were drawn again because no position fitted."""
    beacon = case.beacon
    centre = np.asarray(beacon.center_m, float)
    fov = np.asarray(fov_grid(device_profiles()[PROFILE_ID], config.above_m, 0.05, 0.0).fov_m)
    spread = np.maximum(fov - min(beacon.extent_m), 0.0)
    margin = config.margin_px
    redraws = 0
    while True:
        tilt = rng.uniform(0.0, config.max_tilt_deg)
        azimuth = rng.uniform(0.0, 2 * math.pi)
        yaw = beacon.yaw_deg + rng.uniform(-case.max_yaw_deg, case.max_yaw_deg)
        rotation = rotation_from_ypr(yaw, tilt * math.cos(azimuth), tilt * math.sin(azimuth))
        axis = rotation[:, 2]  # the optical axis in the map
        aimed = centre - axis * centre[2] / axis[2]  # the camera (at z = 0) with the panel's centre on its axis
        for _ in range(config.position_tries):
            xy = aimed[:2] + rng.uniform(-0.5, 0.5, 2) * spread
            pose = CameraPose(position_m=np.array([xy[0], xy[1], 0.0]), rotation_wc=rotation)
            outline = beacon_outline_px(beacon, camera, pose)
            low, high = outline.min(axis=0), outline.max(axis=0)
            if (low > margin).all() and (high < [width - margin, height - margin]).all():
                return pose, redraws
        redraws += 1


def shape_sample(args: tuple[ShapesConfig, str, int]) -> dict:
    config, key, index = args
    case = shape_cases(config.above_m)[key]
    # the uncapped circle sees the very frames of the capped one
    rng = np.random.default_rng([config.seed, index, SHAPES.index(key.removesuffix("-uncapped"))])
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * config.scale), round(profile.height * config.scale)
    camera = intrinsics_from_profile(profile, width, height)
    pose, redraws = draw_shape_pose(config, case, camera, width, height, rng)
    sensor = SensorModel(
        psf_sigma_px=rng.uniform(*config.psf_sigma_px),
        plateau_dn=255.0 * rng.uniform(*config.overexposure),
    )
    pixels = render_frame(case.beacon, camera, pose, width, height, sensor, rng)
    gravity = noisy_gravity(pose.rotation_wc, config.gravity_sigma_deg, rng)
    true_yaw = math.degrees(math.atan2(pose.rotation_wc[1, 0], pose.rotation_wc[0, 0]))
    heading = None
    if case.heading:
        heading = (true_yaw + rng.normal(0.0, config.heading_sigma_deg) + 180.0) % 360.0 - 180.0
    meta = fixture_meta(camera, width, height, pose, gravity_camera=gravity, heading_deg=heading)
    frame = LumaFrame(pixels=pixels, meta=meta, camera=camera)
    pipeline = PipelineOptions(gravity_sigma_deg=config.gravity_sigma_deg, outline_fit=case.outline_fit)
    options = LocateOptions(pipeline=pipeline)
    start = time.perf_counter()
    # the map states the position error it needs (`required_sigma_m`): the outline fit's cap
    beacon_map = BeaconMap(name="bench-shapes", beacons=[case.beacon], required_sigma_m=case.outline_fit.max_sigma_m)
    result = locate(frame, beacon_map, options)
    locate_ms = (time.perf_counter() - start) * 1000.0
    tilt = math.degrees(math.acos(float(np.clip(pose.rotation_wc[2, 2], -1.0, 1.0))))
    sample = {
        "shape": key,
        "index": index,
        "position_m": pose.position_m.tolist(),
        "yaw_deg": true_yaw,
        "relative_yaw_deg": (true_yaw - case.beacon.yaw_deg + 180.0) % 360.0 - 180.0,
        "tilt_deg": tilt,
        "heading_error_deg": None if heading is None else (heading - true_yaw + 180.0) % 360.0 - 180.0,
        "attitude_redraws": redraws,
        "locate_ms": locate_ms,
        "ok": result.ok,
        "outcome": frame_outcome(result),
    }
    if not result.ok:
        return {**sample, "reason": result.reason.value, "message": result.message}
    delta = np.subtract(result.position_m, pose.position_m)
    rotation = np.asarray(result.rotation_wc, float)
    yaw_error = math.degrees(math.atan2(rotation[1, 0], rotation[0, 0])) - true_yaw
    sample.update(
        error_2d_m=float(np.hypot(*delta[:2])),
        error_3d_m=float(np.linalg.norm(delta)),
        error_m=delta.tolist(),
        yaw_error_deg=(yaw_error + 180.0) % 360.0 - 180.0,
        orientation_rule=None if result.orientation_rule is None else result.orientation_rule.value,
    )
    if result.position_covariance_m2 is not None:
        covariance = np.asarray(result.position_covariance_m2, float)[:2, :2]
        sample.update(
            mahalanobis2=float(delta[:2] @ np.linalg.solve(covariance, delta[:2])),
            sigma_2d_m=float(math.sqrt(max(np.linalg.eigvalsh(covariance).max(), 0.0))),
            sigma_rms_2d_m=float(math.sqrt(max(np.trace(covariance), 0.0))),
        )
    return sample


def summarize_shape(samples: list[dict]) -> dict:
    """The table's row of one shape from its samples (see `shape_sample`)."""
    errors = [s["error_2d_m"] if s["ok"] else math.nan for s in samples]
    row = summarize(errors)
    located = [s for s in samples if s["ok"]]
    row["frames"] = len(samples)
    if located:
        row["mean_3d_mm"] = 1000.0 * float(np.mean([s["error_3d_m"] for s in located]))
        row["rms_2d_mm"] = 1000.0 * float(np.sqrt(np.mean([s["error_2d_m"] ** 2 for s in located])))
    with_ellipse = [s for s in located if "mahalanobis2" in s]
    row["with_covariance"] = len(with_ellipse)
    if with_ellipse:
        row["inside_95_pct"] = 100.0 * sum(s["mahalanobis2"] <= CHI2_2DOF_95 for s in with_ellipse) / len(with_ellipse)
        row["mean_sigma_2d_mm"] = 1000.0 * float(np.mean([s["sigma_2d_m"] for s in with_ellipse]))
        row["rms_sigma_2d_mm"] = 1000.0 * float(np.sqrt(np.mean([s["sigma_rms_2d_m"] ** 2 for s in with_ellipse])))
    reasons: dict[str, int] = {}
    for s in samples:
        if not s["ok"]:
            reasons[s["reason"]] = reasons.get(s["reason"], 0) + 1
    row["refusals"] = dict(sorted(reasons.items()))
    rules: dict[str, int] = {}
    for s in located:
        rules[str(s["orientation_rule"])] = rules.get(str(s["orientation_rule"]), 0) + 1
    row["orientation_rules"] = rules
    # a wrong orientation rule turns the fix by 180 degrees (a rectangle) or 90 (a square) about the panel
    row["turned_fixes"] = sum(abs(s["yaw_error_deg"]) > 45.0 for s in located)
    row["median_locate_ms"] = statistics.median(s["locate_ms"] for s in samples) if samples else None
    row["attitude_redraws"] = sum(s["attitude_redraws"] for s in samples)
    yaws = [abs(s["relative_yaw_deg"]) for s in samples]
    row["share_yaw_beyond_45_pct"] = 100.0 * sum(y > 45.0 for y in yaws) / len(yaws) if yaws else None
    return row


def _progress(done: int, total: int, label: str) -> None:
    if sys.stderr.isatty():
        print(f"\r{label}: {done}/{total}", end="\n" if done == total else "", file=sys.stderr, flush=True)
    elif done == total or done % max(1, total // 10) == 0:
        print(f"{label}: {done}/{total}", file=sys.stderr, flush=True)


def _pose_note(sample: dict) -> dict:
    keys = ("index", "position_m", "yaw_deg", "relative_yaw_deg", "tilt_deg", "heading_error_deg")
    note = {k: sample[k] for k in keys}
    note["position_m"] = [round(v, 4) for v in sample["position_m"]]
    note["from_under_panel_m"] = round(math.hypot(*sample["position_m"][:2]), 4)  # the panel is over (0, 0)
    for k in ("yaw_deg", "relative_yaw_deg", "tilt_deg", "heading_error_deg"):
        if note[k] is not None:
            note[k] = round(note[k], 2)
    return note


def _fix_note(sample: dict) -> dict:
    return {
        **_pose_note(sample),
        "error_2d_mm": round(1000 * sample["error_2d_m"], 3),
        "yaw_error_deg": round(sample["yaw_error_deg"], 2),
        "orientation_rule": sample["orientation_rule"],
        "mahalanobis2": sample.get("mahalanobis2"),
        "sigma_2d_mm": round(1000 * sample["sigma_2d_m"], 3) if "sigma_2d_m" in sample else None,
    }


def _frame_note(sample: dict) -> dict:
    outcome = {"outcome": sample["outcome"]}  # unrounded, for `bench results`
    if sample["ok"]:
        return {"shape": sample["shape"], "ok": True, **_fix_note(sample), **outcome}
    return {"shape": sample["shape"], "ok": False, **_pose_note(sample), "reason": sample["reason"], **outcome}


def run_shapes(config: ShapesConfig, workers: int | None = None) -> dict:
    """Render and locate `config.frames` frames of each shape; one row per shape."""
    workers = workers or os.cpu_count() or 1
    cases = shape_cases(config.above_m)
    jobs = [(config, key, index) for index in range(config.frames) for key in config.shapes]
    samples: list[dict] = []
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for sample in pool.map(shape_sample, jobs, chunksize=1):
            samples.append(sample)
            _progress(len(samples), len(jobs), f"shapes at {config.above_m:.1f} m")
    rows = {}
    for key in config.shapes:
        mine = sorted((s for s in samples if s["shape"] == key), key=lambda s: s["index"])
        row = {"label": cases[key].label, "beacon": cases[key].beacon.model_dump(mode="json", exclude_none=True)}
        row.update(summarize_shape(mine))
        refused = [s for s in mine if not s["ok"]]
        row["refused_frames"] = [{**_pose_note(s), "reason": s["reason"], "message": s["message"]} for s in refused]
        located = [s for s in mine if s["ok"]]
        if located:
            worst = max(located, key=lambda s: s["error_2d_m"])
            row["worst_frame"] = _fix_note(worst)
        row["turned_frames"] = [_fix_note(s) for s in located if abs(s["yaw_error_deg"]) > 45.0]
        rows[key] = row
    ordered = sorted(samples, key=lambda s: (config.shapes.index(s["shape"]), s["index"]))
    settings = asdict(config)
    settings["shapes"] = list(config.shapes)
    profile = device_profiles()[PROFILE_ID]
    return {
        "config": settings,
        "frame": f"{round(profile.width * config.scale)}x{round(profile.height * config.scale)}",
        "shapes": rows,
        "frames": [_frame_note(s) for s in ordered],
        "wall_s": time.perf_counter() - start,
        "workers": workers,
        "cpu_count": os.cpu_count(),
        "machine": f"{platform.machine()} {platform.processor() or platform.platform()}",
    }


def format_shapes(report: dict) -> str:
    config = report["config"]
    lines = [
        f"panel shapes {config['above_m']:.1f} m above the camera, frame {report['frame']}, "
        f"{config['frames']} frames each; tilt <= {config['max_tilt_deg']:g} deg, gravity sigma "
        f"{config['gravity_sigma_deg']:g} deg, the circle's heading sigma {config['heading_sigma_deg']:g} deg",
        "(2D error in mm; 3D: its mean; in95: share inside the reported 95 % ellipse; sigma: the ellipse's "
        "mean 1-sigma along its longer axis, mm; ms: median locate time)",
        f"{'shape':<26} {'cover':>6} {'mean':>7} {'std':>7} {'max':>7} {'p95':>7} {'3D':>7} "
        f"{'in95':>6} {'sigma':>7} {'ms':>6}  refusals",
    ]
    for row in report["shapes"].values():
        refusals = ", ".join(f"{reason} {count}" for reason, count in row["refusals"].items()) or "-"
        lines.append(
            f"{row['label']:<26} {row['coverage_pct']:5.1f}% {table_cell(row, 'mean_mm', 7, 2)} {table_cell(row, 'std_mm', 7, 2)} "
            f"{table_cell(row, 'max_mm', 7, 2)} {table_cell(row, 'p95_mm', 7, 2)} {table_cell(row, 'mean_3d_mm', 7, 2)} "
            f"{table_cell(row, 'inside_95_pct', 5, 0)}{'%' if row.get('inside_95_pct') is not None else ' '} "
            f"{table_cell(row, 'mean_sigma_2d_mm', 7, 2)} {table_cell(row, 'median_locate_ms', 6, 0)}  {refusals}"
        )
    for row in report["shapes"].values():
        if row["turned_fixes"]:
            worst = max(row["turned_frames"], key=lambda note: note["error_2d_mm"])
            lines.append(
                f"  {row['label'].strip()}: {row['turned_fixes']} fixes turned about the panel (yaw off by more than "
                f"45 deg); worst: frame {worst['index']}, camera yaw {worst['relative_yaw_deg']} deg from the "
                f"beacon's, {worst['error_2d_mm']} mm"
            )
    lines.append(f"  wall time {report['wall_s']:.0f} s on {plural(report['workers'], 'worker')} (render + locate)")
    return "\n".join(lines)


def run_shapes_command(args: argparse.Namespace) -> int:
    """`lumipose bench accuracy --shape`: the accuracy sub-command's options, one row per shape."""
    frames = 100 if args.frames is None else args.frames
    if frames < 1 or args.scale <= 0:
        return report_bad_input(BadInput("--frames must be at least 1 and --scale positive"), args.json)
    config = ShapesConfig(frames=frames, scale=args.scale, max_tilt_deg=args.max_tilt,
                          gravity_sigma_deg=args.gravity_sigma, seed=args.seed)  # fmt: skip
    report = run_shapes(config, args.workers)
    print(json.dumps(report, indent=2) if args.json else format_shapes(report))
    return 0
