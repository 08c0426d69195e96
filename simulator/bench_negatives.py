"""`lumipose bench negatives`: how often a frame the map does not describe still becomes a fix.

Two parts, figures, not tests (docs/reliability.md, "A fix answers to its own evidence"):

- **Wrong maps** on rendered frames: each panel drawn as it is (`truth`) and located with a map
  that says something else of it (`mapped`): its side 2, 5 or 10 % off, its corner radius off by
  5 to 50 mm, a square mapped as a circle and back, the wrong beacon of a room (the right shape,
  1.2 m away and turned). The same frames located with the right map are the row `right map`:
  its refusals are the false refusals. Per row: the share refused (by reason), the share fixed,
  the 2-D error of those fixed and whether their reported 95 % ellipse holds it. A wrong `side_m`
  alone scales the distance, and the wrong beacon of the same shape moves the fix by the beacons'
  offset; neither changes what one frame shows, so no test of one frame can see them (the survey
  measures sizes, the ID names the beacon).
- **Real photos** of rooms, ceilings and lamps, none of a Lumipose panel
  (`simulator/negatives/photos/manifest.json`: each file's repository, commit, path and licence;
  the shipped ones, and with `--local` those whose licence keeps them out of the repository,
  fetched as the manifest says): each located with a bundled profile against the bundled panels
  (the test bench's and the scenes' 174 mm square at 1.0, 2.72 and 3.0 m, the first beacon named
  where a map has several, as the app may send it; the shapes bench's 600 mm square and
  1200 x 300 mm rectangle) at each `required_sigma_m` from 1 cm to 1 m: any fix is a wrong one.
  A refusal at one sigma is one at every smaller sigma too (the gates only tighten), so only a
  fix is tried again at the next one down.

Poses, rendering and locating are `lumipose bench accuracy --shape`'s (`simulator.bench_shapes`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from server.camera import intrinsics_from_profile
from server.ingest import LumaFrame, read_photo_file
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from server.pose.outline import OutlineFitRules
from shared_schemas import Beacon, BeaconMap, PanelShape, device_profiles
from shared_schemas.cli import BadInput, plural, report_bad_input, table_cell
from simulator.bench_shapes import CHI2_2DOF_95, PROFILE_ID, ShapeCase, ShapesConfig, draw_shape_pose
from simulator.benchmarks import noisy_gravity, progress
from simulator.fixtures import fixture_meta
from simulator.render import SensorModel, render_frame

PHOTOS = Path(__file__).parent / "negatives" / "photos"
SIGMAS_M = (0.01, 0.05, 0.1, 0.5, 1.0)
ABOVE_M = 1.4  # the shapes bench's: a 2.7 m ceiling, the phone at 1.3 m
PROFILE = "xiaomi-mi8-rear"  # the real photos' (a phone's main camera)


@dataclass(frozen=True)
class WrongMap:
    key: str
    label: str
    truth: str  # the drawn panel: a key of `panels()`
    mapped: Beacon  # what the map says of it (id 0, as the drawn one)


def panels(above_m: float = ABOVE_M) -> dict[str, ShapeCase]:
    """The drawn panels (the shapes bench's), `above_m` over the camera."""
    centre = [0.0, 0.0, above_m]
    cases = [
        ShapeCase("square-174", "174 mm square", Beacon(id=0, center_m=centre, side_m=0.174, corner_radius_m=0.02),
                  40.0, False),
        ShapeCase("square-600", "600 mm square", Beacon(id=0, center_m=centre, side_m=0.6, corner_radius_m=0.01),
                  40.0, False),
        ShapeCase("circle-200", "200 mm circle", Beacon(id=0, center_m=centre, shape=PanelShape.circle,
                                                        diameter_m=0.2), 40.0, True),
    ]  # fmt: skip
    return {case.key: case for case in cases}


def wrong_maps(above_m: float = ABOVE_M) -> list[WrongMap]:
    """Each drawn panel with the right map first, then the wrong ones, in the table's order."""
    drawn = panels(above_m)
    rows: list[WrongMap] = []
    for key in ("square-174", "square-600"):
        right = drawn[key].beacon
        side, radius = right.side_m or 0.0, right.corner_radius_m
        rows.append(WrongMap(f"{key}/right", "right map", key, right))
        for factor in (0.9, 0.95, 0.98, 1.02, 1.05, 1.1):
            rows.append(WrongMap(f"{key}/side{factor:g}", f"side x {factor:g}", key,
                                 right.model_copy(update={"side_m": side * factor})))  # fmt: skip
        for offset_mm in (-10, 5, 10, 20, 50):
            wrong = radius + offset_mm / 1000
            if 0 <= wrong < side / 2:
                rows.append(WrongMap(f"{key}/radius{offset_mm:+d}", f"corner radius {offset_mm:+d} mm", key,
                                     right.model_copy(update={"corner_radius_m": wrong})))  # fmt: skip
        rows.append(
            WrongMap(
                f"{key}/as-circle",
                "mapped as a circle",
                key,
                Beacon(id=0, center_m=right.center_m, shape=PanelShape.circle, diameter_m=side),
            )
        )
        # the right shape, the room's other beacon: 1.2 m away and turned a quarter
        rows.append(
            WrongMap(
                f"{key}/other-beacon",
                "another beacon of the room",
                key,
                right.model_copy(update={"center_m": [1.2, 0.0, right.center_m[2]], "yaw_deg": 90.0}),
            )
        )
    circle = drawn["circle-200"].beacon
    rows.append(WrongMap("circle-200/right", "right map", "circle-200", circle))
    rows.append(
        WrongMap(
            "circle-200/as-square",
            "mapped as a square",
            "circle-200",
            Beacon(id=0, center_m=circle.center_m, side_m=0.2, corner_radius_m=0.02),
        )
    )
    return rows


@dataclass(frozen=True)
class NegativesConfig:
    frames: int = 20  # per wrong map
    scale: float = 0.25
    required_sigma_m: float = 0.01  # the wrong maps' (the bundled maps' default)
    seed: int = 1
    photos: bool = True  # the real photos too
    local: Path | None = None  # the manifest's photos that are not shipped, fetched here as it says
    sigmas_m: tuple[float, ...] = SIGMAS_M  # the real photos' maps' required_sigma_m
    shapes: ShapesConfig = field(default_factory=ShapesConfig)


def wrong_map_sample(args: tuple[NegativesConfig, WrongMap, int]) -> dict:
    """One frame of the drawn panel, located with the row's map: the outcome and, for a fix, its error."""
    config, row, index = args
    case = panels()[row.truth]
    # every row of a panel sees the very frames of its right map
    rng = np.random.default_rng([config.seed, index, list(panels()).index(row.truth)])
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * config.scale), round(profile.height * config.scale)
    camera = intrinsics_from_profile(profile, width, height)
    shapes = replace(config.shapes, scale=config.scale)
    pose, _ = draw_shape_pose(shapes, case, camera, width, height, rng)
    sensor = SensorModel(psf_sigma_px=rng.uniform(*shapes.psf_sigma_px),
                         plateau_dn=255.0 * rng.uniform(*shapes.overexposure))  # fmt: skip
    pixels = render_frame(case.beacon, camera, pose, width, height, sensor, rng)
    gravity = noisy_gravity(pose.rotation_wc, shapes.gravity_sigma_deg, rng)
    heading = None
    if case.heading:
        true_yaw = math.degrees(math.atan2(pose.rotation_wc[1, 0], pose.rotation_wc[0, 0]))
        heading = (true_yaw + rng.normal(0.0, shapes.heading_sigma_deg) + 180.0) % 360.0 - 180.0
    meta = fixture_meta(camera, width, height, pose, gravity_camera=gravity, heading_deg=heading)
    frame = LumaFrame(pixels=pixels, meta=meta, camera=camera)
    rules = OutlineFitRules(max_sigma_m=config.required_sigma_m)
    options = LocateOptions(pipeline=PipelineOptions(gravity_sigma_deg=shapes.gravity_sigma_deg, outline_fit=rules))
    beacon_map = BeaconMap(name="bench-negatives", beacons=[row.mapped], required_sigma_m=config.required_sigma_m)
    result = locate(frame, beacon_map, options)
    sample = {"row": row.key, "index": index, "ok": result.ok}
    if not result.ok:
        return {**sample, "reason": result.reason.value, "message": result.message}
    delta = np.subtract(result.position_m, pose.position_m)[:2]
    sample["error_2d_m"] = float(np.hypot(*delta))
    if result.position_covariance_m2 is not None:
        covariance = np.asarray(result.position_covariance_m2, float)[:2, :2]
        sample["mahalanobis2"] = float(delta @ np.linalg.solve(covariance, delta))
        sample["sigma_2d_m"] = float(math.sqrt(max(np.linalg.eigvalsh(covariance).max(), 0.0)))
    return sample


def summarize_row(samples: list[dict]) -> dict:
    """Refused and fixed shares of one row, the fixed ones' errors and their ellipses' coverage."""
    fixed = [s for s in samples if s["ok"]]
    reasons: dict[str, int] = {}
    for s in samples:
        if not s["ok"]:
            reasons[s["reason"]] = reasons.get(s["reason"], 0) + 1
    row: dict = {
        "frames": len(samples),
        "refused_pct": 100.0 * (len(samples) - len(fixed)) / len(samples) if samples else 0.0,
        "fixed_pct": 100.0 * len(fixed) / len(samples) if samples else 0.0,
        "refusals": dict(sorted(reasons.items())),
        "messages": sorted({s["message"] for s in samples if not s["ok"]})[:3],
    }
    if fixed:
        errors = np.array([s["error_2d_m"] for s in fixed]) * 1000
        row.update(mean_mm=float(errors.mean()), max_mm=float(errors.max()))
    with_ellipse = [s for s in fixed if "mahalanobis2" in s]
    if with_ellipse:
        row["inside_95_pct"] = 100.0 * sum(s["mahalanobis2"] <= CHI2_2DOF_95 for s in with_ellipse) / len(with_ellipse)
        row["mean_sigma_mm"] = 1000.0 * float(np.mean([s["sigma_2d_m"] for s in with_ellipse]))
    return row


def bench_maps() -> dict[str, BeaconMap]:
    """The panels the photos are located against, by name."""
    from shared_schemas.cli import read_map_argument
    from simulator.bench_shapes import shape_cases
    from simulator.scene import find_scene

    maps = {"test-bench": read_map_argument("test-bench", None)}
    for name in ("office", "android-bench"):  # paper-bench, walk-one-panel, office-9: the same panel at these heights
        maps[name] = find_scene(name).beacon_map()
    for key in ("square-600", "rectangle-1200x300"):
        maps[key] = BeaconMap(name=key, beacons=[shape_cases()[key].beacon])
    return maps


def photo_rows(path: Path, sigmas_m: tuple[float, ...] = SIGMAS_M) -> list[dict]:
    """One row per (map, sigma) of the photo at `path`; a located one with its `frame_outcome` (`bench
    results` compares it), one refused at a larger sigma without."""
    from server.camera import resolve_profile_args
    from simulator.bench_results import frame_outcome

    profiles, profile = resolve_profile_args([PROFILE])
    frame = read_photo_file(path, profiles, None, profile)[0]
    rows: list[dict] = []
    for name, beacon_map in bench_maps().items():
        beacon_id = beacon_map.beacons[0].id if len(beacon_map.beacons) > 1 else None
        refused = None
        for sigma in sorted(sigmas_m, reverse=True):
            if refused is None:
                asked = beacon_map.model_copy(update={"required_sigma_m": sigma})
                result = locate(frame, asked, beacon_id=beacon_id)
                ok, reason = result.ok, None if result.ok else str(result.reason)
                message = (result.warnings[0] if result.warnings else "") if result.ok else result.message or ""
                outcome = frame_outcome(result)
                if not ok:
                    refused = reason
            else:
                ok, reason, message, outcome = False, refused, "refused at a larger sigma", None
            rows.append({"photo": path.name, "map": name, "sigma_m": sigma, "ok": ok, "reason": reason,
                         "message": message[:200], "outcome": outcome})  # fmt: skip
    return rows


def run_negatives(config: NegativesConfig, workers: int | None = None) -> dict:
    """Both parts: the wrong maps' rows and the real photos' fixes."""
    workers = workers or os.cpu_count() or 1
    rows = wrong_maps()
    jobs = [(config, row, index) for row in rows for index in range(config.frames)]
    start = time.perf_counter()
    samples: list[dict] = []
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for sample in pool.map(wrong_map_sample, jobs, chunksize=2):
            samples.append(sample)
            progress(len(samples), len(jobs), "wrong maps")
    table = {}
    for row in rows:
        mine = [s for s in samples if s["row"] == row.key]
        table[row.key] = {
            "panel": row.truth,
            "label": row.label,
            "mapped": row.mapped.model_dump(mode="json", exclude_none=True),
            **summarize_row(mine),
        }
    settings = asdict(config)
    settings["local"] = None if config.local is None else str(config.local)
    return {
        "config": settings,
        "wrong_maps": table,
        "photos": run_photos(config.local, workers, config.sigmas_m) if config.photos else None,
        "wall_s": time.perf_counter() - start,
        "workers": workers,
        "cpu_count": os.cpu_count(),
        "machine": f"{platform.machine()} {platform.processor() or platform.platform()}",
    }


def run_photos(local: Path | None = None, workers: int = 2, sigmas_m: tuple[float, ...] = SIGMAS_M,
               only: tuple[str, ...] | None = None) -> dict:
    """Locate every photo of the manifest found here (and in `local`), or `only` those files of it; the
    fixes by map and sigma."""
    entries = json.loads((PHOTOS / "manifest.json").read_text())["photos"]
    if only is not None:
        unknown = set(only) - {entry["file"] for entry in entries}
        if unknown:
            raise ValueError(f"not in {PHOTOS / 'manifest.json'}: {', '.join(sorted(unknown))}")
        entries = [entry for entry in entries if entry["file"] in only]
    paths = []
    for entry in entries:
        where = PHOTOS if entry["shipped"] else local
        if where is not None and (where / entry["file"]).is_file():
            paths.append(where / entry["file"])
    start = time.perf_counter()
    with ProcessPoolExecutor(max(1, workers)) as pool:
        rows = [row for rows in pool.map(photo_rows, paths, [sigmas_m] * len(paths)) for row in rows]
    fixes = [row for row in rows if row["ok"]]
    return {
        "photos": len(paths),
        "listed": len(entries),
        "locates": len(rows),
        "fixes": len(fixes),
        "fixes_by_map_sigma": {
            f"{m} {s:g}": n for (m, s), n in sorted(Counter((r["map"], r["sigma_m"]) for r in fixes).items())
        },
        "photos_with_fixes": sorted({r["photo"] for r in fixes}),
        "reasons": dict(Counter(r["reason"] or "fix" for r in rows).most_common()),
        "wall_s": round(time.perf_counter() - start, 1),
        "rows": rows,
    }





def format_negatives(report: dict) -> str:
    config = report["config"]
    lines = [
        f"wrong maps: {config['frames']} frames each at scale {config['scale']:g}, panels {ABOVE_M:g} m above the "
        f"camera, required_sigma_m {config['required_sigma_m']:g}",
        "(refused and fixed: shares of the frames; error: 2-D, mm, of the fixes; in95: share of them inside their "
        "reported 95 % ellipse; sigma: its mean 1-sigma, mm)",
        f"{'panel':<12} {'map':<28} {'refused':>8} {'fixed':>7} {'mean':>8} {'max':>8} {'in95':>6} {'sigma':>6}  "
        "refusals",
    ]
    for row in report["wrong_maps"].values():
        refusals = ", ".join(f"{k} {v}" for k, v in row["refusals"].items()) or "-"
        lines.append(
            f"{row['panel']:<12} {row['label']:<28} {row['refused_pct']:7.0f}% {row['fixed_pct']:6.0f}% "
            f"{table_cell(row, 'mean_mm', 8, 1)} {table_cell(row, 'max_mm', 8, 1)} "
            f"{table_cell(row, 'inside_95_pct', 5, 0)}{'%' if row.get('inside_95_pct') is not None else ' '} "
            f"{table_cell(row, 'mean_sigma_mm', 6, 1)}  {refusals}"
        )
    if report["photos"] is not None:
        lines.append("real photos (maps " + ", ".join(bench_maps()) + "; required_sigma_m "
                     + ", ".join(f"{s:g}" for s in config["sigmas_m"]) + "): " + format_photos(report["photos"]))
    lines.append(f"  wall time {report['wall_s']:.0f} s on {plural(report['workers'], 'worker')}")
    return "\n".join(lines)


def run_negatives_command(args: argparse.Namespace) -> int:
    if args.frames < 1 or args.scale <= 0 or args.required_sigma <= 0 or min(args.sigmas) <= 0:
        return report_bad_input(
            BadInput("--frames must be at least 1, --scale, --required-sigma and --sigmas positive"), args.json
        )
    config = NegativesConfig(frames=args.frames, scale=args.scale, required_sigma_m=args.required_sigma,
                             seed=args.seed, photos=not args.no_photos, local=args.local,
                             sigmas_m=tuple(args.sigmas))  # fmt: skip
    report = run_negatives(config, args.workers)
    print(json.dumps(report, indent=2) if args.json else format_negatives(report))
    return 0


def format_photos(report: dict) -> str:
    lines = [f"{report['photos']} of {report['listed']} photos, {report['locates']} locates, {report['fixes']} fixes "
             f"({report['wall_s']:.0f} s)"]  # fmt: skip
    lines += [f"  fixes {key}: {count}" for key, count in report["fixes_by_map_sigma"].items()]
    lines += [f"  photo with fixes: {name}" for name in report["photos_with_fixes"]]
    lines.append("  outcomes: " + ", ".join(f"{k} {v}" for k, v in report["reasons"].items()))
    return "\n".join(lines)
