"""`lumipose bench robustness` (issue 13, item 2): what each stage of a phone's image chain costs.

The accuracy bench's frames (`simulator.benchmarks.accuracy_frame`: the same poses, PSF,
overexposure and gravity draws for every cell) rendered through a phone's chain
(`simulator.chain.ChainSpec`), one effect at a time on top of "ISP off" (`ChainSpec()`, what
the app asks for: bilinear demosaicing, no noise reduction or sharpening, a linear tone curve,
1 % veiling glare and a 2 % halo), then "ISP on" (`IspSpec.phone()`), at each distance and
scale. The chain's noise comes from its own generator, so every chain cell of a frame draws
the same noise where the frames have the same size. The "panel" group draws a real panel
(`simulator.panels`: a bezel, edge fall-off, a glossy ceiling) or puts a second lamp or a window
near it, through "ISP off" (`panel_effects`). The "phone" group puts defocus, sharpening and JPEG
together (`phone_chain`), still and with tremor, as an outside check did (issue 29 item 4). "no chain" is the renderer's own 8-bit
noise model, as `lumipose bench accuracy` has it (its gravity draw differs: it follows the noise).

Each cell: coverage, mean, p95 and max 2-D error (mm), wrong fixes (> 50 mm) and the
refusal reasons, for the pipeline in its default (auto gravity) mode. The error is against where
the camera was when the rolling shutter read the panel's centre (`benchmarks.position_seen_m`): the
pipeline fits one pose to the frame's outline and does not correct pose frames for the readout, so
with motion ("motion" group) that is what it reports; the cells also give the mean against the
pose at the frame's timestamp (`mean_vs_timestamp_mm`), which the metadata's ground truth is.
"""

from __future__ import annotations

import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from server.fov import fov_grid
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from shared_schemas import device_profiles
from shared_schemas.cli import plural
from simulator.bench_results import frame_outcome
from simulator.benchmarks import (
    PROFILE_ID, AccuracyConfig, accuracy_frame, bench_beacon, bench_motion, position_seen_m, summarize,
)
from simulator.chain import ChainSpec, IspSpec, OpticsSpec, PixelSpec
from simulator.motion import MotionSpec
from simulator.panels import PanelSpec
from simulator.scene import LightSourceSpec

WRONG_FIX_M = 0.05
ISP_OFF = ChainSpec()


def _isp(**update) -> ChainSpec:
    return ChainSpec(isp=IspSpec(**update))


def phone_chain(distance_m: float, motion: MotionSpec | None = None) -> ChainSpec:
    """The stages an outside check put together (issue 29 item 4): focused 25 % too near, `motion`, unsharp-mask
    sharpening 0.8 (`IspSpec.phone`'s) and JPEG 90 on top of "ISP off" (still without `motion`); each alone
    is a cell of its own group."""
    return ChainSpec(optics=OpticsSpec(focus_distance_m=0.75 * distance_m), motion=motion or MotionSpec(),
                     isp=IspSpec(sharpen_amount=0.8), jpeg_quality=90)


def effects(distance_m: float) -> dict[str, tuple[str, ChainSpec | None]]:
    """name -> (effect group, chain) at `distance_m`; the groups are what --effects filters."""
    glare = OpticsSpec()
    return {
        "no chain": ("reference", None),
        "ISP off": ("reference", ISP_OFF),
        # focused too near: of the two ways to be off by a share, the larger disc
        "focus -25%": ("defocus", ChainSpec(optics=OpticsSpec(focus_distance_m=0.75 * distance_m))),
        "focus -50%": ("defocus", ChainSpec(optics=OpticsSpec(focus_distance_m=0.5 * distance_m))),
        "no glare/halo": ("glare", ChainSpec(optics=OpticsSpec(glare_fraction=0.0, halo_fraction=0.0))),
        "glare/halo 3x": ("glare", ChainSpec(optics=OpticsSpec(glare_fraction=3 * glare.glare_fraction,
                                                              halo_fraction=3 * glare.halo_fraction))),
        "binning 2x2": ("binning", ChainSpec(pixels=PixelSpec(binning=2))),
        "demosaic edge-aware": ("demosaic", _isp(demosaic="edge_aware")),
        "NR bilateral": ("noise", _isp(noise_reduction="bilateral")),
        "sharpen 0.5": ("sharpen", _isp(sharpen_amount=0.5)),
        "sharpen 1.0": ("sharpen", _isp(sharpen_amount=1.0)),
        # the preset the app can ask for, reported `srgb` and undone by the server; the S-curve, like
        # "ISP on", is a device's own curve, reported `device`: the cell of a curve nobody can undo
        "tone sRGB (preset)": ("tone", _isp(tone_curve="srgb")),
        "tone S-curve": ("tone", _isp(tone_curve="s_curve")),
        "JPEG 90": ("jpeg", ChainSpec(jpeg_quality=90)),
        "JPEG 75": ("jpeg", ChainSpec(jpeg_quality=75)),
        "tremor": ("motion", ChainSpec(motion=MotionSpec.tremor())),
        "walking": ("motion", ChainSpec(motion=MotionSpec.walking())),
        **dict.fromkeys(panel_effects(distance_m), ("panel", ISP_OFF)),
        "phone still": ("phone", phone_chain(distance_m)),
        "phone tremor": ("phone", phone_chain(distance_m, MotionSpec.tremor())),
        "ISP on": ("reference", ChainSpec(isp=IspSpec.phone())),
    }


GROUPS = ("reference", "defocus", "glare", "binning", "demosaic", "noise", "sharpen", "tone", "jpeg", "motion", "panel",
          "phone")


def panel_effects(distance_m: float) -> dict[str, dict]:
    """The "panel" group's cells: name -> the `AccuracyConfig` fields that draw a real panel (simulator.panels)
    or another light near it. The bench's panel is centred at (0, 0, distance_m), the camera below it."""
    ceiling = distance_m
    beacon = bench_beacon(distance_m)
    wall = fov_grid(device_profiles()[PROFILE_ID], distance_m, 0.05, beacon.size_m).beacon_adjusted_m[1] / 2 + 0.05
    return {
        "bezel white": {"panel": PanelSpec.typical("white").only("bezel")},
        "bezel metal": {"panel": PanelSpec.typical("metal").only("bezel")},
        "edge fall-off": {"panel": PanelSpec.typical().only("falloff")},
        "glossy ceiling": {"panel": PanelSpec.typical(glossy_ceiling=True).only("sheen")},
        # a round ceiling lamp (0.2 m across) as bright as the panel, 0.3 m from its centre: in view in 90-100 %
        # of the 40 first frames at 1 and 2 m, some of them cut by the frame's border
        "second lamp": {"light_sources": (LightSourceSpec(kind="disc", center_m=[0.3, 0.0, ceiling], radius_m=0.1,
                                                          luminance_nits=1000.0, label="second lamp"),)},
        # a window (1.2 x 1.2 m, an overcast sky of 3000 cd/m2 as in the office scene), its top 0.2 m below the
        # ceiling, in the wall just beyond the farthest camera the bench draws (never between camera and panel):
        # in view in 50-58 % of the 40 first frames at 1 and 2 m, always cut by the border, ~9 % of the frame
        "window": {"light_sources": (LightSourceSpec(
            kind="polygon", luminance_nits=3000.0, label="window",
            points_m=[[-0.6, wall, ceiling - 0.2], [0.6, wall, ceiling - 0.2], [0.6, wall, ceiling - 1.4],
                      [-0.6, wall, ceiling - 1.4]]),)},
    }


@dataclass(frozen=True)
class RobustnessConfig:
    distances_m: tuple[float, ...] = (1.0, 2.0)
    scales: tuple[float, ...] = (0.25, 1.0)
    frames: int = 40  # per cell
    effects: tuple[str, ...] = GROUPS  # groups; "reference" (no chain, ISP off, ISP on) is always run
    seed: int = 1


def _sample(args: tuple[AccuracyConfig, int]) -> tuple[float, str | None, float, dict]:
    """(2-D error against the camera when its panel was read, refusal reason, 2-D error against the timestamp's,
    the result's `frame_outcome`)."""
    config, index = args
    frame, beacon_map, pose = accuracy_frame(config, index)
    options = PipelineOptions(gravity_mode=GravityMode.auto, gravity_sigma_deg=config.gravity_sigma_deg)
    result = locate(frame, beacon_map, LocateOptions(pipeline=options))
    if not result.ok:
        return math.nan, result.reason.value, math.nan, frame_outcome(result)
    seen_m = position_seen_m(pose, bench_motion(config, index, frame.meta.height), frame.camera,
                             beacon_map.beacons[0].center_m)
    return (float(np.hypot(*np.subtract(result.position_m, seen_m)[:2])), None,
            float(np.hypot(*np.subtract(result.position_m, pose.position_m)[:2])), frame_outcome(result))


def _panel_fields(fields: dict) -> dict:
    """A panel cell's `AccuracyConfig` fields as JSON for its report row."""
    row = {"panel": fields["panel"].model_dump(mode="json")} if "panel" in fields else {}
    if "light_sources" in fields:
        row["light_sources"] = [light.model_dump(mode="json") for light in fields["light_sources"]]
    return row


def cell_summary(errors_m: list[float], refusals: list[str]) -> dict:
    summary = summarize(errors_m)
    summary["wrong_fixes"] = sum(1 for e in errors_m if math.isfinite(e) and e > WRONG_FIX_M)
    summary["refusals"] = {reason: refusals.count(reason) for reason in sorted(set(refusals))}
    return summary


def run_robustness(config: RobustnessConfig, workers: int | None = None) -> dict:
    """Every cell (effect x distance x scale) of `config`; figures per cell and the targets."""
    workers = workers or os.cpu_count() or 1
    cells = []
    for scale in config.scales:
        for distance in config.distances_m:
            for name, (group, chain) in effects(distance).items():
                if group == "reference" or group in config.effects:
                    cells.append((scale, distance, name, group, chain))
    total = len(cells) * config.frames
    start = time.perf_counter()
    tasks = [(replace(AccuracyConfig(distance_m=distance, frames=config.frames, scale=scale, seed=config.seed),
                      chain=chain, **panel_effects(distance).get(name, {})), i)
             for scale, distance, name, _, chain in cells for i in range(config.frames)]
    rows, results = [], []
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for result in pool.map(_sample, tasks, chunksize=1):
            results.append(result)
            if len(results) % config.frames:
                continue
            scale, distance, name, group, chain = cells[len(rows)]
            errors = [e for e, *_ in results]
            row = {"scale": scale, "distance_m": distance, "effect": name, "group": group,
                   "chain": None if chain is None else chain.model_dump(mode="json"), "frames": config.frames,
                   **_panel_fields(panel_effects(distance).get(name, {})),
                   **cell_summary(errors, [r for _, r, *_ in results if r is not None]),
                   "outcomes": [outcome for *_, outcome in results]}  # per frame, for `bench results`
            if group == "motion":
                row["mean_vs_timestamp_mm"] = summarize([e for _, _, e, _ in results]).get("mean_mm")
            rows.append(row)
            results = []
            print(f"{len(rows) * config.frames}/{total} frames ({time.perf_counter() - start:.0f} s): "
                  f"{scale:g} x, {distance:g} m, {name}: mean {row.get('mean_mm', math.nan):.2f} mm, "
                  f"cover {row['coverage_pct']:.0f} %", file=sys.stderr, flush=True)
    for row in rows:
        base = next((r for r in rows if r["scale"] == row["scale"] and r["distance_m"] == row["distance_m"]
                     and r["effect"] == "ISP off"), None)
        if base and base.get("mean_mm") and row.get("mean_mm") is not None:
            row["mean_over_isp_off"] = row["mean_mm"] / base["mean_mm"]
    return {"frames_per_cell": config.frames, "distances_m": list(config.distances_m), "scales": list(config.scales),
            "seed": config.seed, "mode": "auto", "wrong_fix_mm": 1000 * WRONG_FIX_M, "cells": rows,
            "targets": targets(rows), "wall_s": time.perf_counter() - start, "workers": workers,
            "cpu_count": os.cpu_count()}


def targets(rows: list[dict]) -> list[dict]:
    """Issue 13's targets, each met or not (None: no cell measured it)."""
    def cells(effect: str, scale: float | None = None, distance: float | None = None) -> list[dict]:
        return [r for r in rows if r["effect"] == effect and (scale is None or r["scale"] == scale)
                and (distance is None or r["distance_m"] == distance)]

    found = []

    def check(name: str, chosen: list[dict], ok) -> None:
        found.append({"target": name, "cells": len(chosen), "met": all(ok(r) for r in chosen) if chosen else None})

    check("ISP off: coverage 100 % (quarter resolution, 1 and 2 m)", cells("ISP off", 0.25),
          lambda r: r["coverage_pct"] >= 100.0)
    check("ISP off: mean <= 1 mm at 1 m (quarter)", cells("ISP off", 0.25, 1.0),
          lambda r: r.get("mean_mm", math.inf) <= 1.0)
    check("ISP off: mean <= 3 mm at 2 m (quarter)", cells("ISP off", 0.25, 2.0),
          lambda r: r.get("mean_mm", math.inf) <= 3.0)
    check("ISP on: coverage >= 95 %", cells("ISP on"), lambda r: r["coverage_pct"] >= 95.0)
    check("ISP on: mean <= 3 mm at 1 m", cells("ISP on", distance=1.0), lambda r: r.get("mean_mm", math.inf) <= 3.0)
    check("0 wrong fixes (> 50 mm) in any cell", rows, lambda r: r["wrong_fixes"] == 0)
    return found


def format_robustness(report: dict) -> str:
    lines = [f"{report['frames_per_cell']} frames per cell, mode {report['mode']}, 2-D error in mm; "
             f"x ISP off = mean / the ISP-off cell's; wrong = fixes > {report['wrong_fix_mm']:g} mm",
             f"{'scale':>5} {'dist':>5} {'effect':<20} {'cover':>6} {'mean':>7} {'p95':>7} {'max':>7} "
             f"{'x off':>6} {'wrong':>5}  refusals"]
    for r in report["cells"]:
        refusals = ", ".join(f"{k} {v}" for k, v in r["refusals"].items())
        if "mean_mm" not in r:
            lines.append(f"{r['scale']:>5g} {r['distance_m']:>4g}m {r['effect']:<20} {r['coverage_pct']:5.1f}% "
                         f"{'no fix':>7}{'':>16} {'':>6} {r['wrong_fixes']:>5}  {refusals}")
            continue
        ratio = r.get("mean_over_isp_off")
        lines.append(f"{r['scale']:>5g} {r['distance_m']:>4g}m {r['effect']:<20} {r['coverage_pct']:5.1f}% "
                     f"{r['mean_mm']:7.2f} {r['p95_mm']:7.2f} {r['max_mm']:7.1f} "
                     f"{'' if ratio is None else f'{ratio:5.1f}x':>6} {r['wrong_fixes']:>5}  {refusals}")
    lines.append("targets (issue 13):")
    for t in report["targets"]:
        state = {True: "met", False: "NOT met", None: "not measured"}[t["met"]]
        lines.append(f"  {state:<12} {t['target']}")
    lines.append(f"wall time {report['wall_s']:.0f} s on {plural(report['workers'], 'worker')}")
    return "\n".join(lines)
