"""Benchmark engine and report writers: render a series, locate every frame, tabulate, plot.

Every benchmark (`lumipose bench grid|bench-real|distance|tilt`) is a scene plus a series;
`locate_series` renders each sample in memory (the same frames `lumipose simulate` writes),
runs the pipeline on it and compares with the ground truth. As in the paper (Section IV-B/C)
a fix whose 2D error exceeds the confidence margin (the 0.05 m cell) is an outlier: it counts
against coverage and is left out of the error statistics. The fixes' reported uncertainty is
checked against their errors: the share inside the reported 95 % ellipse (`calibration`).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from server.ingest import LumaFrame
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from shared_schemas import CameraIntrinsics
from shared_schemas.cli import plural
from simulator.benchmarks import calibration, ellipse_test, position_seen_m, summarize
from simulator.sampling import SamplePose, parallel_map, render_pose
from simulator.scene import Scene, readout_motion

OUTLIER_M = 0.05  # the paper's confidence margin: one grid cell


@dataclass(frozen=True)
class Outcome:
    """One sample located: truth, estimate (None = no fix) and why not."""

    index: int
    label: str
    true_m: tuple[float, float, float]
    estimate_m: tuple[float, float, float] | None
    reason: str | None
    message: str | None
    reprojection_px: float | None
    warnings: tuple[str, ...] = ()
    # a moving camera: where it was when the rolling shutter read the panel's centre row
    at_panel_rows_m: tuple[float, float, float] | None = None
    # the XY block of the fix's reported position covariance (m^2), rows
    covariance_xy_m2: tuple[tuple[float, float], tuple[float, float]] | None = None

    @property
    def ellipse_test(self) -> tuple[bool | None, float | None]:
        """(2D error inside the reported 95 % ellipse, reported 2D sigma m); None without a fix or covariance."""
        if self.estimate_m is None:
            return None, None
        return ellipse_test(np.subtract(self.estimate_m[:2], self.true_m[:2]), self.covariance_xy_m2)

    @property
    def error_at_panel_rows_2d_m(self) -> float:
        if self.estimate_m is None or self.at_panel_rows_m is None:
            return math.nan
        return float(np.hypot(self.estimate_m[0] - self.at_panel_rows_m[0],
                              self.estimate_m[1] - self.at_panel_rows_m[1]))

    @property
    def error_2d_m(self) -> float:
        if self.estimate_m is None:
            return math.nan
        return float(np.hypot(self.estimate_m[0] - self.true_m[0], self.estimate_m[1] - self.true_m[1]))

    @property
    def error_3d_m(self) -> float:
        if self.estimate_m is None:
            return math.nan
        return float(np.linalg.norm(np.subtract(self.estimate_m, self.true_m)))


@dataclass(frozen=True)
class LocateJob:
    scene: Scene
    sample: SamplePose
    options: PipelineOptions = PipelineOptions()
    pipeline_camera: CameraIntrinsics | None = None  # what the pipeline is told (None = the truth)


def locate_sample(job: LocateJob) -> Outcome:
    """Render `job.sample` and locate it with the pipeline."""
    pixels, meta = render_pose(job.scene, job.sample)
    camera = job.pipeline_camera or meta.camera
    if job.pipeline_camera is not None:
        meta = meta.model_copy(update={"camera": camera})
    try:
        result = locate(LumaFrame(pixels=pixels, meta=meta, camera=camera), job.scene.beacon_map(),
                        LocateOptions(pipeline=job.options))
    except Exception as error:  # a crash is a finding of the benchmark, not the end of it
        return Outcome(index=job.sample.index, label=job.sample.label, true_m=job.sample.position_m,
                       estimate_m=None, reason="pipeline_error", message=f"{type(error).__name__}: {error}"[:300],
                       reprojection_px=None)
    return Outcome(
        index=job.sample.index, label=job.sample.label, true_m=job.sample.position_m,
        estimate_m=tuple(result.position_m) if result.ok else None,
        reason=None if result.ok else result.reason.value, message=result.message,
        reprojection_px=result.reprojection_error_px, warnings=tuple(result.warnings),
        at_panel_rows_m=_at_panel_rows(job.scene, job.sample, meta.camera),
        covariance_xy_m2=_xy_block(result.position_covariance_m2) if result.ok else None,
    )


def _xy_block(covariance_m2) -> tuple[tuple[float, float], tuple[float, float]] | None:
    if covariance_m2 is None:
        return None
    (a, b), (c, d) = (row[:2] for row in covariance_m2[:2])
    return (float(a), float(b)), (float(c), float(d))


def _at_panel_rows(scene: Scene, sample: SamplePose, camera: CameraIntrinsics) -> tuple[float, float, float] | None:
    """The camera's position when the rows of the nearest panel's centre were exposed (mid-window)."""
    motion = readout_motion(scene, sample.velocity_mps, sample.angular_velocity_dps)
    if motion is None:
        return None
    pose = sample.camera_pose()
    centres = np.array([b.center_m for b in scene.beacons], dtype=float)
    in_camera = (centres - pose.position_m) @ pose.rotation_wc
    ahead = in_camera[:, 2] > 0
    if not ahead.any():
        return None
    nearest = centres[ahead][np.argmin(np.hypot(in_camera[ahead, 0], in_camera[ahead, 1]) / in_camera[ahead, 2])]
    return tuple(float(v) for v in position_seen_m(pose, motion, camera, nearest))


def locate_series(jobs: list[LocateJob], workers: int | None, label: str) -> list[Outcome]:
    return list(parallel_map(locate_sample, jobs, workers, label))


def table(outcomes: list[Outcome], margin_m: float = OUTLIER_M) -> dict:
    """The paper's Table 1/2 figures (mm, %): fixes within the margin only; plus what was lost."""
    errors = [o.error_2d_m for o in outcomes]
    within = [e if e <= margin_m else math.nan for e in errors]
    summary = summarize(within)
    summary.update({
        "samples": len(outcomes),
        "no_fix": sum(o.estimate_m is None for o in outcomes),
        "outliers": sum(math.isfinite(e) and e > margin_m for e in errors),
        "refusals": dict(sorted(_count(o.reason for o in outcomes if o.reason).items())),
        "mean_3d_mm": float(np.nanmean([o.error_3d_m if o.error_2d_m <= margin_m else math.nan
                                        for o in outcomes]) * 1000) if summary.get("mean_mm") is not None else None,
    })
    # the reported uncertainty against the errors it describes, over the fixes within the margin
    summary.update(calibration([o.ellipse_test for o in outcomes if o.error_2d_m <= margin_m]))
    if any(o.at_panel_rows_m is not None for o in outcomes):
        summary["at_panel_rows"] = summarize([e if e <= margin_m else math.nan
                                              for e in (o.error_at_panel_rows_2d_m for o in outcomes)])
    return summary


def _count(items) -> dict[str, int]:
    counts: dict[str, int] = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return counts


def failures(outcomes: list[Outcome], margin_m: float = OUTLIER_M) -> list[dict]:
    """Samples without a fix or beyond the margin, with what the pipeline said."""
    return [{"index": o.index, "label": o.label, "true_m": list(o.true_m),
             "error_2d_mm": None if o.estimate_m is None else round(o.error_2d_m * 1000, 2),
             "reason": o.reason, "message": o.message}
            for o in outcomes if o.estimate_m is None or o.error_2d_m > margin_m]


def write_outcomes(outcomes: list[Outcome], path: Path) -> None:
    rows = [{**asdict(o), "error_2d_mm": o.error_2d_m * 1000, "error_3d_mm": o.error_3d_m * 1000} for o in outcomes]
    path.write_text(json.dumps(rows, indent=1, allow_nan=True) + "\n")


def format_table(summary: dict, title: str) -> str:
    """The summary as the paper's table (mm), as plain text."""
    if "mean_mm" not in summary:
        return f"{title}: no fix within the margin in {plural(summary['samples'], 'sample')} {summary['refusals']}"
    return "\n".join([
        title,
        f"  mean error   {summary['mean_mm']:8.3f} mm",
        f"  std          {summary['std_mm']:8.3f} mm",
        f"  min error    {summary['min_mm']:8.3f} mm",
        f"  max error    {summary['max_mm']:8.3f} mm",
        f"  p95          {summary['p95_mm']:8.3f} mm",
        f"  coverage     {summary['coverage_pct']:8.2f} %  ({plural(summary['samples'], 'sample')}, "
        f"{summary['no_fix']} without a fix, {summary['outliers']} outliers > {OUTLIER_M * 1000:.0f} mm)",
        f"  refusals     {summary['refusals'] or 'none'}",
    ] + _calibration_line(summary) + _panel_rows_line(summary))


def _calibration_line(summary: dict) -> list[str]:
    if "ellipse95_pct" not in summary:
        return []
    return [f"  uncertainty  {summary['ellipse95_pct']:8.2f} % of the 2D errors inside the reported 95 % ellipse "
            f"(calibrated: ~95), mean reported 2D sigma {summary['mean_sigma_2d_mm']:.3f} mm"]


def _panel_rows_line(summary: dict) -> list[str]:
    rows = summary.get("at_panel_rows")
    if not rows or "mean_mm" not in rows:
        return []
    return [f"  against the pose when the panel's rows were read: mean {rows['mean_mm']:.3f} mm, "
            f"max {rows['max_mm']:.3f} mm (a moving camera's rolling shutter)"]


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_scatter(outcomes: list[Outcome], path: Path, title: str, margin_m: float = OUTLIER_M) -> None:
    """Fig. 11/13: true positions (black +), estimates (blue o, red o beyond the margin), no fix (red x).

    A second panel draws each error vector magnified, since millimetre errors vanish at the
    scale of the grid.
    """
    plt = pyplot()
    true = np.array([o.true_m[:2] for o in outcomes])
    fixed = [o for o in outcomes if o.estimate_m is not None]
    estimates = np.array([o.estimate_m[:2] for o in fixed]).reshape(-1, 2)
    errors = np.array([o.error_2d_m for o in fixed])
    missing = np.array([o.true_m[:2] for o in outcomes if o.estimate_m is None]).reshape(-1, 2)
    figure, (left, right) = plt.subplots(1, 2, figsize=(13, 7.5))
    left.plot(true[:, 0], true[:, 1], "k+", markersize=6, label="true position")
    good = errors <= margin_m
    left.plot(estimates[good, 0], estimates[good, 1], "o", mfc="none", mec="tab:blue", markersize=5,
              label="estimate")
    if (~good).any():
        left.plot(estimates[~good, 0], estimates[~good, 1], "o", mfc="none", mec="red", markersize=6,
                  label=f"outlier (> {margin_m * 1000:.0f} mm)")
    if len(missing):
        left.plot(missing[:, 0], missing[:, 1], "x", color="red", markersize=7, label="no fix")
    left.set(xlabel="X (m)", ylabel="Y (m)", title=title, aspect="equal")
    left.legend(loc="upper right", fontsize=8)
    if len(fixed):
        shown = np.clip(errors, 0, margin_m)
        scale_m = 0.02 / max(np.percentile(shown, 95), 1e-5)  # a p95 error is drawn 2 cm long
        delta = (estimates - np.array([o.true_m[:2] for o in fixed])) * scale_m
        quiver = right.quiver(estimates[:, 0] - delta[:, 0] / scale_m, estimates[:, 1] - delta[:, 1] / scale_m,
                              delta[:, 0], delta[:, 1], shown * 1000, angles="xy", scale_units="xy", scale=1,
                              cmap="viridis", width=0.004)
        figure.colorbar(quiver, ax=right, label="2D error (mm)", shrink=0.8)
        right.set(title=f"error vectors x{scale_m:.3g}", xlabel="X (m)", aspect="equal")
        right.set_xlim(left.get_xlim())
        right.set_ylim(left.get_ylim())
    if len(missing):
        right.plot(missing[:, 0], missing[:, 1], "x", color="red", markersize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_heatmap(outcomes: list[Outcome], path: Path, title: str, margin_m: float = OUTLIER_M) -> None:
    """Fig. 12/14: 2D error over the grid (mm); no fix is grey, outliers are clipped at the margin."""
    plt = pyplot()
    true = np.array([o.true_m[:2] for o in outcomes])
    xs, ys = np.unique(np.round(true[:, 0], 6)), np.unique(np.round(true[:, 1], 6))
    grid = np.full((len(ys), len(xs)), np.nan)
    for o, (x, y) in zip(outcomes, true):
        grid[np.searchsorted(ys, round(y, 6)), np.searchsorted(xs, round(x, 6))] = min(o.error_2d_m, margin_m)
    figure, axes = plt.subplots(figsize=(6.5, 7.5))
    cmap = plt.get_cmap("viridis").with_extremes(bad="lightgrey")
    step_x = xs[1] - xs[0] if len(xs) > 1 else 0.05
    step_y = ys[1] - ys[0] if len(ys) > 1 else 0.05
    image = axes.imshow(np.ma.masked_invalid(grid) * 1000, origin="lower", cmap=cmap,
                        extent=[xs[0] - step_x / 2, xs[-1] + step_x / 2, ys[0] - step_y / 2, ys[-1] + step_y / 2])
    figure.colorbar(image, ax=axes, label="2D error (mm); grey = no fix", shrink=0.8)
    axes.set(xlabel="X (m)", ylabel="Y (m)", title=title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_sweep(rows: list[dict], key: str, path: Path, title: str, xlabel: str) -> None:
    """Mean and max 2D error (mm) and coverage (%) against `key` of each row."""
    plt = pyplot()
    x = [row[key] for row in rows]
    figure, error_axes = plt.subplots(figsize=(8, 4.5))
    mean = [row["summary"].get("mean_mm", math.nan) for row in rows]
    peak = [row["summary"].get("max_mm", math.nan) for row in rows]
    error_axes.plot(x, mean, "o-", label="mean 2D error")
    error_axes.plot(x, peak, "s--", label="max 2D error")
    error_axes.set(xlabel=xlabel, ylabel="error (mm)", title=title)
    error_axes.set_yscale("log")
    coverage_axes = error_axes.twinx()
    coverage_axes.plot(x, [row["summary"]["coverage_pct"] for row in rows], "^:", color="tab:green",
                       label="coverage")
    coverage_axes.set(ylabel="coverage (%)", ylim=(0, 105))
    lines = error_axes.get_lines() + coverage_axes.get_lines()
    error_axes.legend(lines, [line.get_label() for line in lines], loc="lower right", fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
