"""`lumipose bench fidelity`: the paper's Fig. 10 between our renderer and an exact projection.

The paper compares the length of the panel's top side in a real and a simulated sample
(Xiaomi Mi 8 rear camera, face to face, 1 m to 3 m in 0.1 m steps) after thresholding both;
it reports a mean ratio of 0.9738 (std 0.0069). Here the two renderings are:
- ours: `simulator.render` (pixel-area coverage, PSF, noise, clipping), measured as the paper
  measures: the side's straight parts located at the 50 % level between background and
  plateau (sub-pixel, per column / row), a line fitted to each, the top side's length between
  its intersections with the left and right sides;
- the exact one: the square's corners projected by a pinhole written here from scratch
  (no OpenCV, no shared geometry code).
Two exposures: the panel below saturation (the 50 % level lies on the true edge) and four
times over it (the clipped edge's 50 % level lies outside the true edge, contract "Physics"),
so the figure also shows how large the clipped-edge effect is.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from server.camera import intrinsics_from_profile
from shared_schemas import Beacon, device_profiles
from simulator.render import CameraPose, SensorModel, render_frame

PAPER_FIG_10 = {"mean_ratio": 0.9738, "std_ratio": 0.0069}


def exact_corners_px(side_m: float, distance_m: float, fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    """Corners (4, 2) of a square of `side_m` centred `distance_m` straight above a pinhole
    looking up (camera x = map X, camera y = map Y): top left, top right, bottom right,
    bottom left in the image (y down)."""
    h = side_m / 2.0
    corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
    return np.array([(cx + fx * x / distance_m, cy + fy * y / distance_m) for x, y in corners])


def _crossing(profile: np.ndarray, level: float, rising: bool) -> float | None:
    """Sub-pixel index where `profile` first crosses `level` (linear between samples)."""
    values = profile if rising else profile[::-1]
    above = np.nonzero(values >= level)[0]
    if len(above) == 0 or above[0] == 0:
        return None
    k = above[0]
    position = k - 1 + (level - values[k - 1]) / (values[k] - values[k - 1])
    return position if rising else len(profile) - 1 - position


def edge_points(image: np.ndarray, level: float, side: str, span: tuple[float, float]) -> np.ndarray:
    """Points (N, 2) of one side at `level`: for each column (top, bottom) or row (left, right)
    inside `span` (pixel indices), the sub-pixel crossing coming from outside the panel."""
    points = []
    for k in range(math.ceil(span[0]), math.floor(span[1]) + 1):
        if side in ("top", "bottom"):
            profile = image[:, k].astype(float)
            middle = len(profile) // 2
            at = _crossing(profile[:middle], level, True) if side == "top" else \
                _crossing(profile[middle:], level, False)
            if at is not None:
                points.append((k, at if side == "top" else at + middle))
        else:
            profile = image[k, :].astype(float)
            middle = len(profile) // 2
            at = _crossing(profile[:middle], level, True) if side == "left" else \
                _crossing(profile[middle:], level, False)
            if at is not None:
                points.append((at if side == "left" else at + middle, k))
    return np.array(points, dtype=float).reshape(-1, 2)


def _fit_line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(point, unit direction) of the total-least-squares line through `points`."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre)
    return centre, vt[0]


def _intersect(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    (p, d), (q, e) = a, b
    t = np.linalg.solve(np.column_stack([d, -e]), q - p)[0]
    return p + t * d


def measured_top_side_px(image: np.ndarray, level: float, corners_hint: np.ndarray, straight_share: float) -> float:
    """The top side's length at `level`: lines fitted to the straight middle of the top, left
    and right sides (`straight_share` of each side, away from the rounded corners), intersected."""
    (x0, y0), (x1, _), (_, y2) = corners_hint[0], corners_hint[1], corners_hint[2]
    margin_x = (x1 - x0) * (1 - straight_share) / 2 + 2
    margin_y = (y2 - y0) * (1 - straight_share) / 2 + 2
    top = _fit_line(edge_points(image, level, "top", (x0 + margin_x, x1 - margin_x)))
    left = _fit_line(edge_points(image, level, "left", (y0 + margin_y, y2 - margin_y)))
    right = _fit_line(edge_points(image, level, "right", (y0 + margin_y, y2 - margin_y)))
    return float(np.linalg.norm(_intersect(top, right) - _intersect(top, left)))


def fidelity_row(distance_m: float, overexposure: float, profile_id: str = "xiaomi-mi8-rear",
                 psf_sigma_px: float = 1.0, seed: int = 0) -> dict:
    """Top-side lengths (px) of one face-to-face view: ours, exact, and their ratio."""
    profile = device_profiles()[profile_id]
    camera = intrinsics_from_profile(profile, profile.width, profile.height)
    beacon = Beacon(id=0, center_m=[0.0, 0.0, distance_m], side_m=0.174, corner_radius_m=0.02)
    sensor = SensorModel(background_dn=8.0, plateau_dn=overexposure * 255.0, psf_sigma_px=psf_sigma_px)
    image = render_frame(beacon, camera, CameraPose(np.zeros(3), np.eye(3)), profile.width, profile.height, sensor,
                         np.random.default_rng([seed, round(distance_m * 1000)]))
    exact = exact_corners_px(beacon.side_m, distance_m, camera.fx, camera.fy, camera.cx, camera.cy)
    plateau = min(sensor.plateau_dn + sensor.background_dn, sensor.saturation_dn)
    level = (sensor.background_dn + plateau) / 2
    straight = 1 - 2 * beacon.corner_radius_m / beacon.side_m
    ours = measured_top_side_px(image, level, exact, straight)
    exact_length = float(np.linalg.norm(exact[1] - exact[0]))
    return {"distance_m": distance_m, "overexposure": overexposure, "ours_px": ours, "exact_px": exact_length,
            "ratio": ours / exact_length}


def blender_row(distance_m: float, profile_id: str = "xiaomi-mi8-rear") -> dict:
    """Top side (px) of the same view rendered by Blender's Cycles, read at its 50 % level."""
    from simulator.blender import render_blender

    profile = device_profiles()[profile_id]
    camera = intrinsics_from_profile(profile, profile.width, profile.height)
    beacon = Beacon(id=0, center_m=[0.0, 0.0, distance_m], side_m=0.174, corner_radius_m=0.02)
    crop = render_blender(beacon, camera, CameraPose(np.zeros(3), np.eye(3)), profile.width, profile.height)
    exact = exact_corners_px(beacon.side_m, distance_m, camera.fx, camera.fy, camera.cx, camera.cy)
    straight = 1 - 2 * beacon.corner_radius_m / beacon.side_m
    blender = measured_top_side_px(crop.radiance, 0.5, exact - crop.origin_px, straight)
    exact_length = float(np.linalg.norm(exact[1] - exact[0]))
    return {"distance_m": distance_m, "overexposure": "blender", "ours_px": blender, "exact_px": exact_length,
            "ratio": blender / exact_length}


def bench_fidelity(figures_dir: Path | None, distances_m: list[float] | None = None,
                   overexposures: tuple[float, ...] = (0.8, 4.0), blender: bool = False) -> dict:
    distances_m = distances_m or [round(1.0 + 0.1 * k, 1) for k in range(21)]
    rows = [fidelity_row(d, o) for o in overexposures for d in distances_m]
    if blender:
        rows += [blender_row(d) for d in distances_m]
        overexposures = (*overexposures, "blender")
    summary = {}
    for o in overexposures:
        ratios = np.array([r["ratio"] for r in rows if r["overexposure"] == o])
        summary[_name(o)] = {"mean_ratio": float(ratios.mean()), "std_ratio": float(ratios.std()),
                              "min_ratio": float(ratios.min()), "max_ratio": float(ratios.max())}
    report = {"title": "simulation fidelity (Fig. 10): top side, our renderer / exact projection",
              "rows": rows, "summary": summary, "paper": PAPER_FIG_10}
    if figures_dir is not None:
        Path(figures_dir).mkdir(parents=True, exist_ok=True)
        figure = Path(figures_dir) / "fidelity.png"
        plot_fidelity(rows, figure)
        report["figures"] = [str(figure)]
    return report


def _name(overexposure) -> str:
    return "Blender (Cycles), unclipped" if overexposure == "blender" else f"ours, panel {overexposure:g}x saturation"


def plot_fidelity(rows: list[dict], path: Path) -> None:
    """The top-side ratio against distance, one line per exposure (and Blender); the legend below."""
    from simulator.reports import pyplot

    plt = pyplot()
    figure, axes = plt.subplots(figsize=(8, 5))
    # lines that coincide (ours unclipped and Blender sit on 1.0) each keep a marker and dash of their own
    for style, o in zip(("o-", "s--", "^:"), dict.fromkeys(r["overexposure"] for r in rows), strict=False):
        part = [r for r in rows if r["overexposure"] == o]
        axes.plot([r["distance_m"] for r in part], [r["ratio"] for r in part], style, mfc="none", label=_name(o))
    axes.axhline(PAPER_FIG_10["mean_ratio"], color="grey", linestyle="--", label="paper: real / Blender, mean")
    axes.axhline(1.0, color="black", linewidth=0.8)
    axes.set(xlabel="distance (m)", ylabel="top side ratio", title="Simulation fidelity: rendered / exact projection",
             ylim=(0.96, 1.02))
    axes.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def format_fidelity(report: dict) -> str:
    lines = [report["title"], f"{'distance':>9} {'exposure':>9} {'ours px':>10} {'exact px':>10} {'ratio':>8}"]
    for r in report["rows"]:
        exposure = "Blender" if r["overexposure"] == "blender" else f"{r['overexposure']:g}x"
        lines.append(f"{r['distance_m']:>8.1f}m {exposure:>9} {r['ours_px']:10.3f} {r['exact_px']:10.3f} "
                     f"{r['ratio']:8.5f}")
    for name, s in report["summary"].items():
        lines.append(f"  {name}: mean {s['mean_ratio']:.5f}, std {s['std_ratio']:.5f}, "
                     f"range {s['min_ratio']:.5f}-{s['max_ratio']:.5f}")
    lines.append(f"  paper (real / Blender): mean {PAPER_FIG_10['mean_ratio']}, std {PAPER_FIG_10['std_ratio']}")
    return "\n".join(lines)
