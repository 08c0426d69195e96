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
import sys
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


def print_figures(paths: list[Path] | list[str], as_json: bool) -> None:
    """Every command that draws says where: "figure PATH" lines on stdout (stderr under --json, whose
    stdout is the report)."""
    for path in paths:
        print(f"  figure {path}", file=sys.stderr if as_json else sys.stdout)


def plain_log_axis(axis) -> None:
    """Decimal tick labels (0.2, 1, 50) on a log axis instead of 2x10^-1; the minor ticks labelled only
    when the axis spans less than two decades (call it once the limits are set)."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    low, high = sorted(axis.get_view_interval())
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(FuncFormatter(_minor_label) if low > 0 and math.log10(high / low) < 2.0
                             else NullFormatter())


def _minor_label(value: float, _position) -> str:
    """2, 3 and 5 times a power of ten: enough to read a value, few enough not to crowd."""
    mantissa = round(value / 10.0 ** math.floor(math.log10(value)), 6) if value > 0 else 0
    return f"{value:g}" if mantissa in (2, 3, 5) else ""


def nice_length(value: float) -> float:
    """The largest 1-2-5 number not above `value` (a reference arrow's length)."""
    if not value > 0:
        return 1.0
    power = 10.0 ** math.floor(math.log10(value))
    return max(step * power for step in (1.0, 2.0, 5.0) if step * power <= value * (1 + 1e-9))


def plot_scatter(outcomes: list[Outcome], path: Path, title: str, margin_m: float = OUTLIER_M) -> None:
    """Fig. 11/13, readable at millimetres: left, each error as an arrow at its true position, magnified
    by a stated factor, with a labelled reference arrow; right, every error from its own true position
    (mm), so that errors a hundred times smaller than the grid's cells can be compared. No fix: red x."""
    plt = pyplot()
    true = np.array([o.true_m[:2] for o in outcomes]).reshape(-1, 2)
    fixed = [o for o in outcomes if o.estimate_m is not None]
    offsets_mm = np.array([np.subtract(o.estimate_m[:2], o.true_m[:2]) for o in fixed]).reshape(-1, 2) * 1000
    at_m = np.array([o.true_m[:2] for o in fixed]).reshape(-1, 2)
    errors_mm = np.hypot(offsets_mm[:, 0], offsets_mm[:, 1])
    good = errors_mm <= margin_m * 1000
    missing = np.array([o.true_m[:2] for o in outcomes if o.estimate_m is None]).reshape(-1, 2)
    figure, (vectors, spread) = plt.subplots(1, 2, figsize=(13, 6.8), gridspec_kw={"width_ratios": [1.25, 1]})
    vectors.plot(true[:, 0], true[:, 1], "+", color="0.6", markersize=4, label="true position", zorder=1)
    if good.any():
        reference_mm = nice_length(float(np.percentile(errors_mm[good], 95)))
        magnify = 0.6 * _spacing_m(true) / (reference_mm / 1000)  # a p95-sized error spans ~0.6 of a cell
        shown = offsets_mm[good] / 1000 * magnify
        quiver = vectors.quiver(at_m[good, 0], at_m[good, 1], shown[:, 0], shown[:, 1], errors_mm[good],
                                angles="xy", scale_units="xy", scale=1, cmap="viridis", width=0.004, zorder=2)
        vectors.quiverkey(quiver, 0.82, 1.015, reference_mm / 1000 * magnify, f"{reference_mm:g} mm error",
                          labelpos="E", coordinates="axes", color="black", fontproperties={"size": 8})
        figure.colorbar(quiver, ax=vectors, label="2D error (mm)", shrink=0.8)
        reach = float(np.abs(shown).max()) + 0.5 * _spacing_m(true)  # the longest arrow stays inside the axes
        vectors.set_xlim(true[:, 0].min() - reach, true[:, 0].max() + reach)
        vectors.set_ylim(true[:, 1].min() - reach, true[:, 1].max() + reach)
        vectors.set_title(f"{title}\nerror vectors, drawn {magnify:.0f}x their length", fontsize=10, loc="left")
    else:
        vectors.set_title(title, fontsize=10, loc="left")
    if (~good).any():
        vectors.plot(at_m[~good, 0], at_m[~good, 1], "o", mfc="none", mec="red", markersize=7,
                     label=f"outlier (> {margin_m * 1000:.0f} mm)", zorder=3)
    if len(missing):
        vectors.plot(missing[:, 0], missing[:, 1], "x", color="red", markersize=7, label="no fix", zorder=3)
    vectors.set(xlabel="X (m)", ylabel="Y (m)", aspect="equal")
    vectors.legend(loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=3, fontsize=8, frameon=False)
    spread.axhline(0, color="0.7", linewidth=0.8)
    spread.axvline(0, color="0.7", linewidth=0.8)
    if good.any():
        spread.scatter(offsets_mm[good, 0], offsets_mm[good, 1], s=10, c=errors_mm[good], cmap="viridis",
                       alpha=0.8, label="estimate - truth")
        p95 = float(np.percentile(errors_mm[good], 95))
        spread.add_patch(plt.Circle((0, 0), p95, fill=False, linestyle="--", color="black", linewidth=0.8,
                                    label=f"p95 {p95:.2f} mm"))
        reach = 1.15 * float(errors_mm[good].max())
        spread.set_xlim(-reach, reach)
        spread.set_ylim(-reach, reach)
        spread.legend(loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=2, fontsize=8, frameon=False)
    lost = f"not shown: {len(missing)} without a fix, {int((~good).sum())} outliers" if len(missing) or (~good).any() \
        else "every sample fixed within the margin"
    spread.set(xlabel="X error (mm)", ylabel="Y error (mm)", aspect="equal")
    spread.set_title(f"each error from its own true position\n{int(good.sum())} fixes; {lost}", fontsize=10,
                     loc="left")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def _spacing_m(points: np.ndarray) -> float:
    """The typical distance between neighbouring points (the grid's cell), for sizing arrows."""
    if len(points) < 2:
        return OUTLIER_M
    gaps = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(gaps, np.inf)
    return float(np.median(gaps.min(axis=1))) or OUTLIER_M


def plot_heatmap(outcomes: list[Outcome], path: Path, title: str, cell_m: float = OUTLIER_M,
                 planned_m: np.ndarray | None = None, margin_m: float = OUTLIER_M) -> dict:
    """Fig. 12/14: 2D error (mm) in cells of `cell_m` at the samples run; outliers clipped at the margin.

    Cells with no fix (red) are told apart from cells not run (hatched): a `--limit` run or a few stored
    samples cover part of the grid (`planned_m`: every position of the full series, for the extent), and
    coverage is over what was run. Returns the counts drawn: {"run", "no_fix", "not_run"} cells.
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    plt = pyplot()
    run = np.array([o.true_m[:2] for o in outcomes]).reshape(-1, 2)
    extent_points = run if planned_m is None else np.vstack([run, np.asarray(planned_m)[:, :2]])
    origin = extent_points.min(axis=0)
    columns, rows = (np.rint((extent_points.max(axis=0) - origin) / cell_m).astype(int) + 1).tolist()
    cells = np.rint((run - origin) / cell_m).astype(int)
    errors: dict[tuple[int, int], list[float]] = {}
    for outcome, (i, j) in zip(outcomes, cells, strict=True):
        errors.setdefault((int(j), int(i)), []).append(outcome.error_2d_m)
    error = np.full((rows, columns), np.nan)
    no_fix = np.zeros((rows, columns), dtype=bool)
    for (j, i), values in errors.items():
        fixed = [v for v in values if math.isfinite(v)]
        if fixed:
            error[j, i] = min(float(np.mean(fixed)), margin_m) * 1000
        else:
            no_fix[j, i] = True
    counts = {"run": len(errors), "no_fix": int(no_fix.sum()), "not_run": rows * columns - len(errors)}
    figure, axes = plt.subplots(figsize=(6.5, 7.8))
    extent = (origin[0] - cell_m / 2, origin[0] + (columns - 0.5) * cell_m,
              origin[1] - cell_m / 2, origin[1] + (rows - 0.5) * cell_m)
    axes.add_patch(plt.Rectangle((extent[0], extent[2]), extent[1] - extent[0], extent[3] - extent[2],
                                 facecolor="white", edgecolor="0.75", hatch="///", zorder=0))
    image = axes.imshow(np.ma.masked_invalid(error), origin="lower", cmap="viridis", extent=extent, zorder=1,
                        vmin=0, interpolation="nearest")
    axes.imshow(np.ma.masked_where(~no_fix, no_fix), origin="lower", cmap=ListedColormap(["tab:red"]),
                extent=extent, zorder=1, interpolation="nearest")
    figure.colorbar(image, ax=axes, label=f"2D error (mm), clipped at {margin_m * 1000:.0f} mm", shrink=0.8)
    fixed_cells = counts["run"] - counts["no_fix"]
    axes.set(xlabel="X (m)", ylabel="Y (m)")
    axes.set_title(f"{title}\n{fixed_cells} of {counts['run']} cells run have a fix "
                   f"({100 * fixed_cells / max(counts['run'], 1):.1f} %), {cell_m * 1000:g} mm cells", fontsize=10)
    axes.legend(handles=[Patch(facecolor="tab:red", label=f"no fix ({counts['no_fix']})"),
                         Patch(facecolor="white", edgecolor="0.6", hatch="///",
                               label=f"not run ({counts['not_run']})")],
                loc="upper left", bbox_to_anchor=(0.0, -0.07), ncol=2, fontsize=8, frameon=False)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return counts


def plot_sweep(rows: list[dict], key: str, path: Path, title: str, xlabel: str) -> None:
    """Mean and max 2D error (mm, log) and coverage (%) against `key` of each row; the legend below."""
    plt = pyplot()
    x = [row[key] for row in rows]
    figure, error_axes = plt.subplots(figsize=(8, 5))
    mean = [row["summary"].get("mean_mm", math.nan) for row in rows]
    peak = [row["summary"].get("max_mm", math.nan) for row in rows]
    error_axes.plot(x, mean, "o-", label="mean 2D error")
    error_axes.plot(x, peak, "s--", label="max 2D error")
    error_axes.set(xlabel=xlabel, ylabel="error (mm, log scale)", title=title)
    error_axes.set_yscale("log")
    plain_log_axis(error_axes.yaxis)
    coverage_axes = error_axes.twinx()
    coverage_axes.plot(x, [row["summary"]["coverage_pct"] for row in rows], "^:", color="tab:green",
                       label="coverage")
    coverage_axes.set(ylabel="coverage (%)", ylim=(0, 105))
    lines = error_axes.get_lines() + coverage_axes.get_lines()
    error_axes.legend(lines, [line.get_label() for line in lines], loc="upper center", bbox_to_anchor=(0.5, -0.13),
                      ncol=3, fontsize=8, frameon=False)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
