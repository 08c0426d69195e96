"""`lumipose bench partial`: panels cut by the image border (issue 11).

The accuracy bench's frames (Xiaomi Mi 8 front camera, 0.174 m panel with 0.02 m corner
radius, tilt uniform up to 10 degrees in any direction, yaw within +-40 degrees, PSF and
overexposure drawn per frame, gravity with a 0.1 degree sensor error, located in the default
`auto` gravity mode), but with the camera moved sideways until the panel's exact projected
outline has the drawn share of its area inside the image: share s in 20-95 % (stratified over
the frames of a cell), a direction in the image the panel leaves through, and a bisection on
the lateral offset along it. With the camera under the panel the panel must be wholly in the
frame, otherwise the pose is drawn again; so is a pose whose bisection misses s.

Each (resolution, distance) cell is tabulated per visible-share bin: coverage, 2D error
(mean, p95, max of every fix, none left out), fixes off by > 50 mm, the share of 2D errors
inside the reported 95 % ellipse (XY block of `position_covariance_m2`, d^T C^-1 d <= 5.991;
a fix without one is "n/a") and the refusals by reason. Every frame's outcome is in the
report (`frames`), for plots.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from shared_schemas import Beacon, BeaconMap, CameraIntrinsics, device_profiles
from simulator.bench_results import frame_outcome
from simulator.benchmarks import PROFILE_ID, AccuracyConfig, noisy_gravity, bench_beacon
from simulator.fixtures import fixture_meta
from simulator.render import CameraPose, SensorModel, beacon_outline_px, exact_polygon_area_px, render_frame
from simulator.sampling import parallel_map

SHARE_RANGE = (0.20, 0.95)
BINS = ((0.20, 0.40), (0.40, 0.60), (0.60, 0.80), (0.80, 0.95))
OFF_M = 0.05  # a fix off by more is counted apart ("> 50 mm")
CHI2_95_2D = 5.991  # 95 % quantile of chi-square with 2 degrees of freedom
SHARE_TOLERANCE = 1e-3  # the bisection stops within this of the drawn share
NO_REASON = "(no reason)"  # a refusal without a reason: a bug the table must show
ACCURACY = AccuracyConfig()
QUARTER = 0.25  # the issue's streaming resolution (970 x 1296)


@dataclass(frozen=True)
class PartialConfig:
    distances_m: tuple[float, ...] = (1.0, 2.0, 3.0)
    scales: tuple[float, ...] = (1.0, QUARTER)  # of the profile's native resolution
    frames: int = 40  # per (scale, distance) cell
    seed: int = 1
    max_tilt_deg: float = ACCURACY.max_tilt_deg
    max_yaw_deg: float = ACCURACY.max_yaw_deg
    psf_sigma_px: tuple[float, float] = ACCURACY.psf_sigma_px
    overexposure: tuple[float, float] = ACCURACY.overexposure
    gravity_sigma_deg: float = ACCURACY.gravity_sigma_deg


@dataclass(frozen=True)
class PartialPose:
    pose: CameraPose
    visible_share: float  # of the projected outline's area inside the image
    target_share: float
    direction_deg: float  # image direction (x right, y down) the panel leaves the frame through
    tilt_deg: float
    yaw_deg: float


def frame_size(scale: float) -> tuple[int, int]:
    profile = device_profiles()[PROFILE_ID]
    return round(profile.width * scale), round(profile.height * scale)


def clip_to_frame(outline_px: np.ndarray, width: int, height: int) -> np.ndarray:
    """The closed polygon (N, 2) cut to the frame's pixel area [-0.5, width - 0.5] x [-0.5, height - 0.5]
    (Sutherland-Hodgman against the four sides; exact for the convex frame)."""
    polygon = np.asarray(outline_px, dtype=float)
    for axis, bound, keep_below in (
        (0, -0.5, False),
        (0, width - 0.5, True),
        (1, -0.5, False),
        (1, height - 0.5, True),
    ):
        if len(polygon) == 0:
            break
        following = np.roll(polygon, -1, axis=0)
        a, b = polygon[:, axis] - bound, following[:, axis] - bound
        if keep_below:
            a, b = -a, -b
        a_in, b_in = a >= 0, b >= 0
        crossing = a_in != b_in
        t = np.where(crossing, a / np.where(crossing, a - b, 1.0), 0.0)
        points = polygon + t[:, None] * (following - polygon)
        # each edge contributes its start when inside, then its crossing when it crosses
        pieces = np.stack([polygon, points], axis=1)
        mask = np.stack([a_in, crossing], axis=1)
        polygon = pieces[mask]
    return polygon


def visible_share(outline_px: np.ndarray, width: int, height: int) -> float:
    """Share of the outline's area inside the frame."""
    inside = clip_to_frame(outline_px, width, height)
    return exact_polygon_area_px(inside) / exact_polygon_area_px(outline_px) if len(inside) >= 3 else 0.0


def cut_borders(outline_px: np.ndarray, width: int, height: int) -> list[str]:
    """The frame's sides the outline crosses."""
    low, high = outline_px.min(axis=0), outline_px.max(axis=0)
    return [
        name
        for name, cut in (
            ("left", low[0] < -0.5),
            ("right", high[0] > width - 0.5),
            ("top", low[1] < -0.5),
            ("bottom", high[1] > height - 0.5),
        )
        if cut
    ]


def draw_partial_pose(
    config: PartialConfig,
    beacon: Beacon,
    camera: CameraIntrinsics,
    width: int,
    height: int,
    share: float,
    rng: np.random.Generator,
) -> PartialPose:
    """A camera pose under `beacon` whose view has `share` of the panel's projected area inside the frame.

    Tilt and yaw are drawn as `bench accuracy` draws them, then a direction in the image; the
    camera moves along the opposite direction (in the map's horizontal plane) so that the
    panel's image leaves the frame along it, by the offset that leaves `share` of it inside.
    """
    if not SHARE_RANGE[0] <= share <= SHARE_RANGE[1]:
        raise ValueError(f"visible share {share} is outside {SHARE_RANGE}")
    while True:
        tilt = rng.uniform(0.0, config.max_tilt_deg)
        azimuth = rng.uniform(0.0, 2 * math.pi)
        yaw = rng.uniform(-config.max_yaw_deg, config.max_yaw_deg)
        rotation = rotation_from_ypr(yaw, tilt * math.cos(azimuth), tilt * math.sin(azimuth))
        direction = rng.uniform(0.0, 2 * math.pi)
        # moving the camera along its own -x/-y moves the panel's image along +x/+y
        along = rotation @ np.array([-math.cos(direction), -math.sin(direction), 0.0])
        along[2] = 0.0
        along /= np.linalg.norm(along)

        def pose_at(offset_m: float, rotation=rotation, along=along) -> CameraPose:
            return CameraPose(position_m=along * offset_m, rotation_wc=rotation)

        def share_at(offset_m: float) -> float:
            return visible_share(beacon_outline_px(beacon, camera, pose_at(offset_m)), width, height)

        if share_at(0.0) < 1.0:
            continue  # the panel is not wholly in the frame with the camera under it
        inside, outside = 0.0, beacon.size_m
        while share_at(outside) >= share and outside < 20.0 * beacon.center_m[2]:
            inside, outside = outside, 2.0 * outside
        for _ in range(60):
            middle = 0.5 * (inside + outside)
            reached = share_at(middle)
            if reached >= share:
                inside = middle
            else:
                outside = middle
            if abs(reached - share) <= SHARE_TOLERANCE / 2:
                break
        if abs(reached - share) > SHARE_TOLERANCE:
            continue
        return PartialPose(pose_at(middle), reached, share, math.degrees(direction), tilt, yaw)


def stratified_share(index: int, frames: int, rng: np.random.Generator) -> float:
    """Frame `index` of a cell of `frames` draws its share uniformly in the index-th of `frames` equal
    slices of the range: uniform over the range, and every bin gets its share of the frames."""
    low, high = SHARE_RANGE
    return low + (high - low) * (index + rng.uniform()) / frames


def _partial_sample(args: tuple[PartialConfig, float, float, int]) -> dict:
    config, scale, distance_m, index = args
    rng = np.random.default_rng([config.seed, index, round(distance_m * 1000), round(scale * 1000)])
    width, height = frame_size(scale)
    camera = intrinsics_from_profile(device_profiles()[PROFILE_ID], width, height)
    beacon = bench_beacon(distance_m)
    share = stratified_share(index, config.frames, rng)
    drawn = draw_partial_pose(config, beacon, camera, width, height, share, rng)
    sensor = SensorModel(
        psf_sigma_px=rng.uniform(*config.psf_sigma_px), plateau_dn=255.0 * rng.uniform(*config.overexposure)
    )
    pixels = render_frame(beacon, camera, drawn.pose, width, height, sensor, rng)
    gravity = noisy_gravity(drawn.pose.rotation_wc, config.gravity_sigma_deg, rng)
    meta = fixture_meta(camera, width, height, drawn.pose, gravity_camera=gravity)
    options = PipelineOptions(gravity_mode=GravityMode.auto, gravity_sigma_deg=config.gravity_sigma_deg)
    result = locate(
        LumaFrame(pixels=pixels, meta=meta, camera=camera),
        BeaconMap(name="bench", beacons=[beacon]),
        LocateOptions(pipeline=options),
    )
    record = {
        "scale": scale,
        "distance_m": distance_m,
        "index": index,
        "visible_share": drawn.visible_share,
        "direction_deg": drawn.direction_deg,
        "borders": cut_borders(beacon_outline_px(beacon, camera, drawn.pose), width, height),
        "tilt_deg": drawn.tilt_deg,
        "yaw_deg": drawn.yaw_deg,
        "position_m": drawn.pose.position_m.tolist(),
        "ok": result.ok,
        "reason": None,
        "message": None,
        "error_2d_mm": None,
        "error_3d_mm": None,
        "sigma_mm": None,
        "mahalanobis2": None,
        "inside_95": None,
        "warnings": list(result.warnings),
        "outcome": frame_outcome(result),  # for `bench results`
    }
    if not result.ok:
        record["reason"] = result.reason.value if result.reason is not None else NO_REASON
        record["message"] = result.message
        return record
    delta = np.subtract(result.position_m, drawn.pose.position_m)
    record["error_2d_mm"] = float(np.hypot(*delta[:2])) * 1000.0
    record["error_3d_mm"] = float(np.linalg.norm(delta)) * 1000.0
    if result.position_sigma_m is not None:
        record["sigma_mm"] = [s * 1000.0 for s in result.position_sigma_m]
    if result.position_covariance_m2 is not None:
        record["mahalanobis2"] = mahalanobis2(delta[:2], np.asarray(result.position_covariance_m2)[:2, :2])
        if record["mahalanobis2"] is not None:
            record["inside_95"] = record["mahalanobis2"] <= CHI2_95_2D
    return record


def mahalanobis2(delta_m: np.ndarray, covariance_m2: np.ndarray) -> float | None:
    """d^T C^-1 d, or None when C is not positive definite (no ellipse to be inside of)."""
    try:
        lower = np.linalg.cholesky(covariance_m2)
    except np.linalg.LinAlgError:
        return None
    whitened = np.linalg.solve(lower, delta_m)
    return float(whitened @ whitened)


def summarize_frames(records: list[dict]) -> dict:
    """Coverage, 2D error, > 50 mm, 95 % ellipse and refusals of `records` (one frame each)."""
    fixes = [r for r in records if r["ok"]]
    errors = np.array([r["error_2d_mm"] for r in fixes])
    judged = [r["inside_95"] for r in fixes if r["inside_95"] is not None]
    summary = {
        "frames": len(records),
        "fixed": len(fixes),
        "coverage_pct": 100.0 * len(fixes) / len(records) if records else None,
        "mean_mm": float(errors.mean()) if len(errors) else None,
        "p95_mm": float(np.percentile(errors, 95)) if len(errors) else None,
        "max_mm": float(errors.max()) if len(errors) else None,
        "over_50mm": int((errors > OFF_M * 1000.0).sum()),
        "inside_95_pct": 100.0 * sum(judged) / len(judged) if judged else None,
        "inside_95": sum(judged),
        "ellipse_na": len(fixes) - len(judged),  # fixes without a usable covariance
        "refusals": dict(Counter(r["reason"] or NO_REASON for r in records if not r["ok"]).most_common()),
    }
    return summary


def _bin_label(low: float, high: float) -> str:
    return f"{low * 100:.0f}-{high * 100:.0f}"


def _in_bin(share: float, low: float, high: float) -> bool:
    return low <= share < high or (high == BINS[-1][1] and share == high)


def issue_summary(records: list[dict]) -> dict:
    """The issue's targets: of panels >= 40 % visible, share fixed (>= 95 %), mean 2D error at 1 m and
    2 m at quarter resolution (<= 2 and <= 5 mm); fixes off by > 50 mm at any share (0)."""
    visible = [r for r in records if r["visible_share"] >= 0.40]
    fixed = [r for r in visible if r["ok"]]

    def quarter_mean(distance_m: float) -> float | None:
        cell = [r for r in fixed if math.isclose(r["scale"], QUARTER) and math.isclose(r["distance_m"], distance_m)]
        return float(np.mean([r["error_2d_mm"] for r in cell])) if cell else None

    mean_1m, mean_2m = quarter_mean(1.0), quarter_mean(2.0)
    share = 100.0 * len(fixed) / len(visible) if visible else None
    over = sum(1 for r in records if r["ok"] and r["error_2d_mm"] > OFF_M * 1000.0)
    return {
        "visible_40_frames": len(visible),
        "visible_40_fixed_pct": share,
        "quarter_1m_mean_mm": mean_1m,
        "quarter_2m_mean_mm": mean_2m,
        "over_50mm": over,
        "met": {
            "fixed_95pct": share is not None and share >= 95.0,
            "quarter_1m_2mm": mean_1m is not None and mean_1m <= 2.0,
            "quarter_2m_5mm": mean_2m is not None and mean_2m <= 5.0,
            "none_over_50mm": over == 0,
        },
    }


def run_partial(config: PartialConfig, workers: int | None = None) -> dict:
    """Render and locate `config.frames` cut-panel frames per (scale, distance); tables per share bin."""
    jobs = [
        (config, scale, distance, i)
        for scale in config.scales
        for distance in config.distances_m
        for i in range(config.frames)
    ]
    records = list(parallel_map(_partial_sample, jobs, workers, "partial"))
    cells = []
    for scale in config.scales:
        width, height = frame_size(scale)
        for distance in config.distances_m:
            cell = [r for r in records if r["scale"] == scale and r["distance_m"] == distance]
            rows = [
                {
                    "visible": _bin_label(low, high),
                    **summarize_frames([r for r in cell if _in_bin(r["visible_share"], low, high)]),
                }
                for low, high in BINS
            ]
            cells.append(
                {
                    "scale": scale,
                    "frame": f"{width}x{height}",
                    "distance_m": distance,
                    "bins": rows,
                    "all": summarize_frames(cell),
                }
            )
    return {
        "title": "cut panels (lumipose bench partial)",
        "config": asdict(config),
        "cells": cells,
        "summary": issue_summary(records),
        "frames": records,
    }


def _mm(value: float | None) -> str:
    return f"{value:7.2f}" if value is not None else f"{'-':>7}"


def format_partial(report: dict) -> str:
    """The text table: one row per resolution, distance and visible-share bin, then the issue's summary."""
    lines = [
        f"{report['title']}: 2D error (mm), auto gravity mode, seed {report['config']['seed']}",
        f"{'frame':>9} {'dist':>5} {'visible':>7} {'frames':>6} {'cover':>6} {'mean':>7} {'p95':>7} "
        f"{'max':>7} {'>50mm':>5} {'in95':>5} {'n/a':>3}  refusals",
    ]
    for cell in report["cells"]:
        for row in [*cell["bins"], {**cell["all"], "visible": "all"}]:
            refusals = ", ".join(f"{reason} {count}" for reason, count in row["refusals"].items())
            cover = f"{row['coverage_pct']:5.1f}%" if row["frames"] else f"{'-':>6}"
            inside = f"{row['inside_95_pct']:4.0f}%" if row["inside_95_pct"] is not None else f"{'-':>5}"
            lines.append(
                f"{cell['frame']:>9} {cell['distance_m']:4.1f}m {row['visible']:>7} {row['frames']:6d} "
                f"{cover} {_mm(row['mean_mm'])} {_mm(row['p95_mm'])} {_mm(row['max_mm'])} "
                f"{row['over_50mm']:5d} {inside} {row['ellipse_na']:3d}  {refusals}"
            )
    s = report["summary"]

    def verdict(met: bool) -> str:
        return "met" if met else "NOT met"

    fixed = f"{s['visible_40_fixed_pct']:.1f} %" if s["visible_40_fixed_pct"] is not None else "n/a"
    mean_1m = f"{s['quarter_1m_mean_mm']:.2f} mm" if s["quarter_1m_mean_mm"] is not None else "no fix"
    mean_2m = f"{s['quarter_2m_mean_mm']:.2f} mm" if s["quarter_2m_mean_mm"] is not None else "no fix"
    lines.append(
        f"issue 11, panels >= 40 % visible ({s['visible_40_frames']} frames): fixed {fixed} (target >= 95 %, "
        f"{verdict(s['met']['fixed_95pct'])}); quarter resolution mean 1 m {mean_1m} (<= 2 mm, "
        f"{verdict(s['met']['quarter_1m_2mm'])}), 2 m {mean_2m} (<= 5 mm, {verdict(s['met']['quarter_2m_5mm'])}); "
        f"fixes > 50 mm at any share: {s['over_50mm']} (target 0, {verdict(s['met']['none_over_50mm'])})"
    )
    return "\n".join(lines)


def plot_partial(report: dict, path: Path) -> None:
    """2D error against visible share, one panel per resolution, coloured by distance; refusals as x
    along the bottom."""
    from simulator.reports import plain_log_axis, pyplot

    plt = pyplot()
    scales = report["config"]["scales"]
    distances = report["config"]["distances_m"]
    colours = {d: plt.get_cmap("viridis")(i / max(1, len(distances) - 1)) for i, d in enumerate(distances)}
    figure, axes = plt.subplots(1, len(scales), figsize=(6.5 * len(scales), 4.8), squeeze=False)
    floor_mm = 0.01
    for panel, scale in zip(axes[0], scales, strict=True):
        width, height = frame_size(scale)
        for distance in distances:
            cell = [r for r in report["frames"] if r["scale"] == scale and r["distance_m"] == distance]
            fixes = [r for r in cell if r["ok"]]
            refused = [r for r in cell if not r["ok"]]
            panel.plot(
                [100 * r["visible_share"] for r in fixes],
                [max(r["error_2d_mm"], floor_mm) for r in fixes],
                "o",
                color=colours[distance],
                mfc="none",
                label=f"{distance:g} m ({len(fixes)} fixes)" if fixes else "_nolegend_",
            )
            panel.plot(
                [100 * r["visible_share"] for r in refused],
                [floor_mm * 1.5] * len(refused),
                "x",
                color=colours[distance],
                label=f"{distance:g} m refused ({len(refused)})" if refused else "_nolegend_",
            )
        panel.axhline(OFF_M * 1000, color="red", linestyle=":", linewidth=1, label=f"{OFF_M * 1000:g} mm: off")
        panel.set_yscale("log")
        panel.set(
            xlim=(15, 100),
            ylim=(floor_mm, 1000),
            xlabel="visible share of the panel's area (%)",
            ylabel="2D error (mm)",
            title=f"{width} x {height}",
        )
        plain_log_axis(panel.yaxis)
        panel.legend(fontsize=7, loc="upper right")
    figure.suptitle("cut panels: error against visible share (x = refused)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
