"""`lumipose bench results save|compare DIR [--quick]`: issue 30's "results unchanged", shown by re-running.

The accuracy, shapes, partial, robustness, vlc (and its cut panels) and office benches run through their
own run functions at fixed seeds and sizes (`QUICK`: a few frames of each, minutes; `FULL`: every
configuration of the figures in docs/*.md at reduced frame counts, tens of minutes); so do frames we did not
make: `bench negatives`' real room photos against its maps (a few in QUICK, every shipped one in FULL), the
real rolling-shutter frame (tests/fixtures/rolling_shutter/), and with `--real-leds-cache DIR` Luxapose's
LED photos (`bench real-leds`). Each bench gives its
per-frame outcomes (`frame_outcome` of every `locate` result, or its trials' decisions) under a key of its
report; `save` writes them with the benches' summary figures and reports into DIR, `compare` runs the same
cases again and holds them against DIR:
- a decision changed (fix or refusal and its reason, beacon ID and where it came from, the orientation rule,
  the gravity prior used, a VLC trial's ID, confidence and frames needed): fails, the frames listed; an
  unconfident VLC reading's best guess is no decision (listed apart, not failing);
- a position (a fix, office's filtered track) moved by more than `TOLERANCE_MM` (0.01 mm, the 3-D distance):
  fails;
- other per-frame numbers (VLC chips seen) and the summary figures: shown side by side, never failing.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

TOLERANCE_MM = 0.01
FIGURE_EPSILON = 1e-6  # summary figures closer than this (in their units) are listed as the same
RESULTS_FILE = "results.json"
SHOWN_CHANGES = 10  # changed frames listed per case


def frame_outcome(result) -> dict:
    """What `bench results` compares of one `server.locator.locate` result (a `LocateResult`): its decision and
    its position (map frame, m; None without a fix)."""
    def value(enum):
        return None if enum is None else enum.value

    return {"ok": result.ok, "reason": value(result.reason), "beacon_id": result.beacon_id,
            "id_source": value(result.beacon_id_source), "orientation_rule": value(result.orientation_rule),
            "gravity_used": result.gravity_used,
            "position_m": None if result.position_m is None else [float(v) for v in result.position_m]}


@dataclass(frozen=True)
class Case:
    """One bench configuration: `bench` (a key of `RUNNERS`) with `params` at a fixed seed."""

    name: str
    bench: str
    params: dict = field(default_factory=dict)


# Per-frame records: {"frame": key, "decision": {...} (identical or failing), "positions_m": {name: [x, y, z]}
# (within TOLERANCE_MM), "figures": {name: number} (shown)}.
def _located(key: str, outcome: dict) -> dict:
    decision = {k: v for k, v in outcome.items() if k != "position_m"}
    positions = {} if outcome["position_m"] is None else {"fix": outcome["position_m"]}
    return {"frame": key, "decision": decision, "positions_m": positions, "figures": {}}


def _figures(prefix: str, source: dict, keys: tuple[str, ...]) -> dict:
    return {f"{prefix} {k}": source[k] for k in keys if isinstance(source.get(k), int | float)}


def _run_accuracy(params: dict, workers: int | None) -> tuple[list, list, dict]:
    from simulator.bench_robustness import phone_chain
    from simulator.benchmarks import AccuracyConfig, run_accuracy

    reports: list[dict] = []
    frames: list[dict] = []
    figures: dict = {}
    for distance in params["distances_m"]:
        config = AccuracyConfig(distance_m=distance, frames=params["frames"], scale=params.get("scale", 1.0),
                                seed=params.get("seed", 1), gravity_sigma_deg=params.get("gravity_sigma_deg", 0.1),
                                chain=phone_chain(distance) if params.get("chain") == "phone" else None)
        report = run_accuracy(config, workers)
        reports.append(report)
        for frame in report["outcomes"]:
            frames += [_located(f"{distance:g}m/{frame['index']}/{mode}", frame[mode]) for mode in report["modes"]]
        for mode, summary in report["modes"].items():
            figures |= _figures(f"{distance:g}m {mode}", summary, ("coverage_pct", "mean_mm", "p95_mm", "max_mm",
                                                                   "ellipse95_pct", "mean_sigma_2d_mm"))
    return reports, frames, figures


def _run_shapes(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    from simulator.bench_shapes import ShapesConfig, run_shapes

    report = run_shapes(ShapesConfig(frames=params["frames"], scale=params.get("scale", 1.0),
                                     seed=params.get("seed", 1)), workers)
    frames = [_located(f"{note['shape']}/{note['index']}", note["outcome"]) for note in report["frames"]]
    figures: dict = {}
    for key, row in report["shapes"].items():
        figures |= _figures(key, row, ("coverage_pct", "mean_mm", "p95_mm", "max_mm", "inside_95_pct",
                                       "mean_sigma_2d_mm", "turned_fixes"))
    return report, frames, figures


def _run_partial(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    from simulator.bench_partial import PartialConfig, run_partial

    config = PartialConfig(distances_m=tuple(params["distances_m"]), scales=tuple(params["scales"]),
                           frames=params["frames"], seed=params.get("seed", 1))
    report = run_partial(config, workers)
    frames = [_located(f"{r['scale']:g}x/{r['distance_m']:g}m/{r['index']}", r["outcome"]) for r in report["frames"]]
    figures = _figures("issue 11", report["summary"], ("visible_40_fixed_pct", "quarter_1m_mean_mm",
                                                       "quarter_2m_mean_mm", "over_50mm"))
    for cell in report["cells"]:
        figures |= _figures(f"{cell['scale']:g}x {cell['distance_m']:g}m", cell["all"],
                            ("coverage_pct", "mean_mm", "p95_mm", "max_mm", "inside_95_pct"))
    return report, frames, figures


def _run_robustness(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    from simulator.bench_robustness import GROUPS, RobustnessConfig, run_robustness

    config = RobustnessConfig(distances_m=tuple(params["distances_m"]), scales=tuple(params["scales"]),
                              frames=params["frames"], effects=tuple(params.get("effects", GROUPS)),
                              seed=params.get("seed", 1))
    report = run_robustness(config, workers)
    frames: list[dict] = []
    figures: dict = {}
    for row in report["cells"]:
        cell = f"{row['scale']:g}x/{row['distance_m']:g}m/{row['effect']}"
        frames += [_located(f"{cell}/{i}", outcome) for i, outcome in enumerate(row["outcomes"])]
        figures |= _figures(cell, row, ("coverage_pct", "mean_mm", "p95_mm", "max_mm", "wrong_fixes"))
    return report, frames, figures


def _run_vlc(params: dict, workers: int | None) -> tuple[list, list, dict]:
    from simulator.bench_vlc import VlcConfig, run_vlc

    reports: list[dict] = []
    frames: list[dict] = []
    figures: dict = {}
    base = VlcConfig(trials=params["trials"], seed=params.get("seed", 1), shape=params.get("shape", "square"),
                     max_frames=params.get("max_frames", 12), map_ids=params.get("map_ids", 0))
    for depth in params.get("depths", [base.depth]):
        for side in params.get("sides_m", [base.side_m]):
            for distance in params["distances_m"]:
                for exposure in params.get("exposures_s", [base.exposure_s]):
                    config = replace(base, distance_m=distance, side_m=side, depth=depth, exposure_s=exposure)
                    report = run_vlc(config, workers)
                    reports.append(report)
                    point = f"{side:g}m/{distance:g}m/depth {depth:g}/{exposure:.3g}s"
                    for i, trial in enumerate(report["trials_run"]):
                        decision = {"id": trial["id"], "map": trial["map"], "foreign": trial["foreign"],
                                    "single": trial["single"][:2], "combined": trial["combined"][:3]}
                        frames.append({"frame": f"{point}/{i}", "decision": decision, "positions_m": {},
                                       "figures": {"single chips": trial["single"][2],
                                                   "combined chips": trial["combined"][3]}})
                    for kind in ("single", "combined"):
                        figures |= _figures(f"{point} {kind}", report[kind], (
                            "success_pct", "confident_wrong", "no_decision", "mean_frames", "mean_captures"))
                        figures |= _figures(f"{point} {kind} map", report[kind].get("map", {}),
                                            ("read_pct", "named_wrong", "foreign_confident"))
    return reports, frames, figures


def _run_vlc_cut(params: dict, workers: int | None) -> tuple[list, list, dict]:
    from simulator.bench_vlc import CutConfig, run_cut

    reports: list[dict] = []
    frames: list[dict] = []
    figures: dict = {}
    for edge, shares in params["shares"].items():
        for share in shares:
            for depth in params.get("depths", [CutConfig.depth]):
                report = run_cut(CutConfig(share=share, edge=edge, trials=params["trials"], depth=depth,
                                           seed=params.get("seed", 1)), workers)
                reports.append(report)
                point = f"{edge}/{share:g}/depth {depth:g}"
                for i, r in enumerate(report["trials_run"]):
                    decision = {k: r[k] for k in ("id", "found", "rows", "named", "refusal")}
                    decision["located"] = r["error_mm"] is not None
                    frames.append({"frame": f"{point}/{i}", "decision": decision,
                                   "positions_m": {"fix": r["position_m"]} if "position_m" in r else {},
                                   "figures": {} if r["chips"] is None else {"chips": r["chips"]}})
                figures |= _figures(point, report, ("named_pct", "named_wrong", "located", "mean_mm", "max_mm"))
    return reports, frames, figures


OFFICE_DECISION = ("ok", "reason", "in_view", "beacon_id", "source", "true_beacon", "vlc_id", "vlc_confident",
                   "outlier")


def _run_office(params: dict, workers: int | None) -> tuple[list, list, dict]:
    from simulator.bench_office import OfficeConfig, run_office

    config = OfficeConfig(pose_scale=params.get("pose_scale"), max_captures=params.get("limit"),
                          seed=params.get("seed", 1), depth=params.get("depth"))
    reports = run_office(config, tuple(params["walks"]), workers)
    frames: list[dict] = []
    figures: dict = {}
    for report in reports:
        walk = report["config"]["walk"]
        for i, r in enumerate(report["records"]):
            positions = {name: r[key] for name, key in (("fix", "fix_m"), ("filtered", "filtered_m")) if key in r}
            figures_of = {} if r.get("vlc_confidence") is None else {"vlc confidence": r["vlc_confidence"]}
            frames.append({"frame": f"{walk}/{i}", "decision": {k: r.get(k) for k in OFFICE_DECISION},
                           "positions_m": positions, "figures": figures_of})
        s = report["summary"]
        figures |= _figures(walk, s, ("coverage_pct", "id_errors", "ids_by_vlc", "ids_carried", "outliers",
                                      "transition_coverage_pct"))
        figures |= _figures(f"{walk} fixes", s["fixes"], ("mean_mm", "p95_mm", "max_mm"))
        figures |= _figures(f"{walk} filtered", s["filtered"], ("mean_mm", "p95_mm", "max_mm"))
    return reports, frames, figures


def _run_photos(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    """`bench negatives`' real room photos, each against each bundled map at each sigma: its decision (a
    refusal at a larger sigma stands for the smaller ones, not located again) and, for a fix, its position."""
    from simulator.bench_negatives import SIGMAS_M, run_photos

    only = params.get("photos")
    report = run_photos(None, workers or os.cpu_count() or 1, tuple(params.get("sigmas_m", SIGMAS_M)),
                        None if only is None else tuple(only))
    frames = []
    for row in report["rows"]:
        key = f"{row['photo']}/{row['map']}/{row['sigma_m']:g}"
        if row["outcome"] is None:
            frames.append({"frame": key, "decision": {"ok": False, "reason": row["reason"], "at_larger_sigma": True},
                           "positions_m": {}, "figures": {}})
        else:
            frames.append(_located(key, row["outcome"]))
    return report, frames, _figures("photos", report, ("photos", "locates", "fixes"))


def _stripes_read(key: str, read: dict, located: dict | None = None) -> dict:
    """One ID frame's read (`bench_real_leds.read_frame`): the blobs, whether each one's stripes were
    measured, the refusals and the reader's answer decide; the stripes' numbers are shown."""
    decision = {"blobs": [[*b["box"], b["hidden_outline"], b["cut_off"], b.get("stripes", "measured")]
                          for b in read["blobs"]],
                "refused": read["refused"], "panels_read": read["panels_read"], "problem": read["problem"]}
    figures = {f"blob {i} {name}": b[name] for i, b in enumerate(read["blobs"])
               for name in ("frequency_hz", "duty") if name in b}
    record = {"frame": key, "decision": decision, "positions_m": {}, "figures": figures}
    if located is not None:
        fix = _located(key, located)
        record |= {"decision": decision | {"locate": fix["decision"]}, "positions_m": fix["positions_m"]}
    return record


def _run_real_leds(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    """Luxapose's real LED photos (`bench real-leds`) from the cache `params["cache"]` (fetched there if
    missing), each read as stored and turned."""
    from simulator.bench_real_leds import bench_real_leds

    report = bench_real_leds(Path(params["cache"]))
    frames = [_stripes_read(f"{row['photo']}/{how}", row[how])
              for row in report["photos"] for how in ("stripes_along_rows", "turned")]
    return report, frames, _figures("real LEDs", report, ("leds_found",))


# tests/fixtures/rolling_shutter/README.md: its exposure and readout, and the room its test locates in
ROLLING_SHUTTER_FRAME = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "rolling_shutter" / \
    "nikon1j1_1000hz_luma.png"
ROLLING_SHUTTER_EXPOSURE_S = 1 / 16000
ROLLING_SHUTTER_SKEW_S = 15.730e-3


def _run_rolling_shutter(params: dict, workers: int | None) -> tuple[dict, list, dict]:
    """The real rolling-shutter frame (an LED at 1 kHz through a diffuser), as taken and turned: its read
    as an ID frame and `locate`'s decision in a two-panel room."""
    import cv2

    from server.locator import locate
    from shared_schemas import Beacon, BeaconMap
    from simulator.bench_real_leds import id_frame, read_frame

    pixels = cv2.imread(str(ROLLING_SHUTTER_FRAME), cv2.IMREAD_UNCHANGED)
    if pixels is None:
        raise FileNotFoundError(f"cannot read {ROLLING_SHUTTER_FRAME}")
    room = BeaconMap(name="room", beacons=[Beacon(id=i, center_m=[2.0 * i, 0.0, 2.5], side_m=0.6) for i in (17, 42)])
    reports: dict = {}
    frames = []
    for how, view in (("as taken", pixels), ("turned", pixels.T)):
        frame = id_frame(view, ROLLING_SHUTTER_EXPOSURE_S, ROLLING_SHUTTER_SKEW_S)
        reports[how] = read_frame(frame)
        frames.append(_stripes_read(f"nikon1j1/{how}", reports[how], frame_outcome(locate(frame, room))))
    return reports, frames, {}


RUNNERS = {"accuracy": _run_accuracy, "shapes": _run_shapes, "partial": _run_partial, "robustness": _run_robustness,
           "vlc": _run_vlc, "vlc-cut": _run_vlc_cut, "office": _run_office, "photos": _run_photos,
           "real-leds": _run_real_leds, "rolling-shutter": _run_rolling_shutter}
BENCHES = tuple(RUNNERS)

# A few frames of every bench: minutes on two loaded cores, for a branch's every change.
QUICK = (
    Case("accuracy-full", "accuracy", {"distances_m": [1.0, 2.0, 3.0], "frames": 3, "scale": 1.0}),
    Case("accuracy-quarter", "accuracy", {"distances_m": [1.0, 2.0, 3.0], "frames": 6, "scale": 0.25}),
    Case("shapes-full", "shapes", {"frames": 2, "scale": 1.0}),
    Case("shapes-quarter", "shapes", {"frames": 4, "scale": 0.25}),
    Case("partial", "partial", {"distances_m": [1.0, 2.0, 3.0], "scales": [1.0, 0.25], "frames": 3}),
    Case("robustness-quarter", "robustness", {"distances_m": [1.0, 2.0], "scales": [0.25], "frames": 1}),
    Case("vlc", "vlc", {"distances_m": [1.0, 2.0, 3.0], "trials": 4}),
    Case("vlc-map", "vlc", {"distances_m": [2.0], "trials": 4, "map_ids": 4}),
    Case("vlc-depth", "vlc", {"distances_m": [3.0], "trials": 3, "depths": [1.0], "max_frames": 24}),
    Case("vlc-rect", "vlc", {"distances_m": [2.0], "trials": 3, "shape": "rect", "sides_m": [1.2]}),
    Case("vlc-circle", "vlc", {"distances_m": [1.5], "trials": 3, "shape": "circle", "sides_m": [0.2]}),
    Case("vlc-cut", "vlc-cut", {"shares": {"bottom": [0.5], "side": [0.6]}, "trials": 2}),
    Case("office", "office", {"walks": ["zigzag", "spiral"], "limit": 6}),
    # slam-ch11_data_7 against the 600 mm square: an outline no view pins down (docs/performance.md)
    Case("photos", "photos", {"photos": ["slam-ch11_data_7.jpg", "slam-ch5_rgbd_color_1.jpg",
                                         "exif-heic_mobile_iphone_13_pro_max.jpg",
                                         "atag-test_data_33369213973_9d9bb4cc96_c.jpg"]}),
    Case("real-leds", "real-leds"),
    Case("rolling-shutter", "rolling-shutter"),
)

# The configurations of the figures in docs/*.md (accuracy.md, vlc.md, performance.md), fewer frames: tens of
# minutes, and every shipped real photo. Left out: the Blender renderer (needs bpy, minutes a frame), bench
# negatives' wrong maps and its photos not shipped (their licences), grid, survey.
FULL = (
    Case("accuracy-full", "accuracy", {"distances_m": [1.0, 2.0, 3.0], "frames": 20, "scale": 1.0}),
    Case("accuracy-seed2", "accuracy", {"distances_m": [1.0, 2.0, 3.0], "frames": 10, "seed": 2}),
    Case("accuracy-gravity-0.5", "accuracy", {"distances_m": [1.0, 3.0], "frames": 10, "gravity_sigma_deg": 0.5}),
    Case("accuracy-quarter", "accuracy", {"distances_m": [1.0, 2.0, 3.0], "frames": 20, "scale": 0.25}),
    Case("accuracy-phone-chain", "accuracy", {"distances_m": [1.0, 2.0], "frames": 8, "scale": 0.25,
                                              "chain": "phone"}),
    Case("shapes-full", "shapes", {"frames": 10, "scale": 1.0}),
    Case("shapes-quarter", "shapes", {"frames": 20, "scale": 0.25}),
    Case("partial", "partial", {"distances_m": [1.0, 2.0, 3.0], "scales": [1.0, 0.25], "frames": 10}),
    Case("robustness-quarter", "robustness", {"distances_m": [1.0, 2.0], "scales": [0.25], "frames": 8}),
    Case("robustness-full", "robustness", {"distances_m": [1.0, 2.0], "scales": [1.0], "frames": 1,
                                           "effects": ["tone", "glare"]}),
    Case("vlc", "vlc", {"distances_m": [1.0, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0], "trials": 10}),
    Case("vlc-0.6m", "vlc", {"distances_m": [1.0, 2.0, 3.0], "trials": 6, "sides_m": [0.6]}),
    Case("vlc-exposure", "vlc", {"distances_m": [1.5], "trials": 6, "exposures_s": [0.000125, 0.00025, 0.0004]}),
    Case("vlc-rect", "vlc", {"distances_m": [1.5, 2.0, 2.5, 3.0], "trials": 6, "shape": "rect", "sides_m": [1.2]}),
    Case("vlc-circle", "vlc", {"distances_m": [1.0, 1.5, 2.0, 2.5, 3.0], "trials": 6, "shape": "circle",
                               "sides_m": [0.2]}),
    Case("vlc-depth", "vlc", {"distances_m": [1.0, 2.0, 3.0], "trials": 6, "depths": [0.3, 0.6, 1.0]}),
    Case("vlc-depth-24frames", "vlc", {"distances_m": [3.0], "trials": 6, "depths": [1.0], "max_frames": 24}),
    Case("vlc-map", "vlc", {"distances_m": [1.0, 2.0, 3.0], "trials": 10, "map_ids": 4}),
    Case("vlc-cut", "vlc-cut", {"shares": {"bottom": [0.3, 0.5, 0.7, 0.9], "side": [0.2, 0.4, 0.6]}, "trials": 4}),
    Case("office", "office", {"walks": ["zigzag", "spiral"]}),
    Case("office-quarter", "office", {"walks": ["zigzag"], "pose_scale": 0.25, "limit": 24}),
    Case("office-depth-1", "office", {"walks": ["zigzag"], "limit": 12, "depth": 1.0}),
    Case("photos", "photos"),
    Case("real-leds", "real-leds"),
    Case("rolling-shutter", "rolling-shutter"),
)


def _git(*args: str) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=Path(__file__).resolve().parent, capture_output=True, text=True,
                             check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    return out.stdout.strip()


def code_version() -> dict:
    """The commit, whether the work tree differs from it, and the tree of the located code (server/ and
    shared_schemas/: equal trees, the same pipeline)."""
    return {"commit": _git("rev-parse", "--short", "HEAD"), "dirty": bool(_git("status", "--porcelain")),
            "server_tree": _git("rev-parse", "--short", "HEAD:server"),
            "shared_schemas_tree": _git("rev-parse", "--short", "HEAD:shared_schemas")}


def run_cases(cases: tuple[Case, ...], workers: int | None, folder: Path | None = None) -> dict:
    """Every case's per-frame records, summary figures and wall time; with `folder`, each case's bench
    reports as FOLDER/<case>.json."""
    runs: dict[str, dict] = {}
    for case in cases:
        start = time.perf_counter()
        print(f"bench results: {case.name} ({case.bench})", file=sys.stderr, flush=True)
        try:
            reports, frames, figures = RUNNERS[case.bench](case.params, workers)
        except Exception as error:  # a bench that fails on a branch is that case's result, the others still run
            runs[case.name] = {"bench": case.bench, "params": case.params, "error": f"{type(error).__name__}: {error}"}
            print(f"bench results: {case.name} failed: {error}", file=sys.stderr, flush=True)
            continue
        runs[case.name] = {"bench": case.bench, "params": case.params, "frames": frames, "figures": figures,
                           "wall_s": time.perf_counter() - start}
        if folder is not None:
            (folder / f"{case.name}.json").write_text(json.dumps(reports, indent=1, default=float) + "\n")
    return runs


def selected(mode: str, benches: list[str] | None, real_leds_cache: Path | None = None) -> tuple[Case, ...]:
    """The mode's cases (only those of `benches`); Luxapose's photos (not shipped: no licence) only from
    `real_leds_cache`, skipped with a printed reason without it."""
    cases = tuple(c for c in (QUICK if mode == "quick" else FULL) if benches is None or c.bench in benches)
    if real_leds_cache is None:
        skipped = [c.name for c in cases if c.bench == "real-leds"]
        if skipped:
            print(f"bench results: {', '.join(skipped)} skipped: Luxapose's photos are not shipped (no licence); "
                  "--real-leds-cache DIR reads them from DIR (fetched there when missing)", file=sys.stderr)
        return tuple(c for c in cases if c.bench != "real-leds")
    return tuple(replace(c, params=c.params | {"cache": str(real_leds_cache)}) if c.bench == "real-leds" else c
                 for c in cases)


def save(folder: Path | None, mode: str, workers: int | None, benches: list[str] | None = None,
         real_leds_cache: Path | None = None) -> dict:
    """Run the cases; with `folder`, write them there (RESULTS_FILE and each case's bench reports)."""
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    runs = run_cases(selected(mode, benches, real_leds_cache), workers, folder)
    saved = {"mode": mode, "code": code_version(), "workers": workers or os.cpu_count(), "cpu_count": os.cpu_count(),
             "tolerance_mm": TOLERANCE_MM, "wall_s": time.perf_counter() - start, "runs": runs}
    if folder is not None:
        (folder / RESULTS_FILE).write_text(json.dumps(saved, indent=1) + "\n")
    return saved


def _max_move_mm(before: dict, after: dict) -> float:
    """The longest move (mm) of any of a frame's positions (name -> [x, y, z] m) between `before` and `after`."""
    moves = [math.dist(after[name], before[name]) for name in before.keys() & after.keys()]
    return 1000.0 * max(moves, default=0.0)


def _decided(decision: dict) -> dict:
    """`decision` without the best guess of an unconfident VLC reading (a trial's "single"/"combined" [id,
    confident, ...], office's vlc_id): no ID was decided, which of the near-equal IDs came first is not a
    decision (a changed guess is listed apart, not failing)."""
    out = dict(decision)
    for kind in ("single", "combined"):
        if isinstance(out.get(kind), list) and out[kind][1] is False:
            out[kind] = [None, *out[kind][1:]]
    if out.get("vlc_confident") is False:
        out["vlc_id"] = None
    return out


def compare_run(base: dict, now: dict) -> dict:
    """One case now against its baseline: changed decisions, the largest move of a position, the per-frame
    numbers' and summary figures' differences; `ok` unless a decision changed, a position moved by more
    than TOLERANCE_MM or the frames are not the same ones (or the bench failed)."""
    if "error" in base or "error" in now:
        return {"frames": 0, "changed": [], "missing": [], "added": [], "max_move_mm": 0.0, "worst_frame": None,
                "moved": [], "guesses_changed": [], "max_number_difference": {}, "figures": {}, "wall_s": [None, None],
                "ok": False,
                "error": now.get("error") or f"the baseline's: {base['error']}"}
    before = {f["frame"]: f for f in base["frames"]}
    after = {f["frame"]: f for f in now["frames"]}
    changed: list[dict] = []
    guesses: list[str] = []
    moves: list[tuple[float, str]] = []
    numbers: dict[str, float] = {}
    for key in before.keys() & after.keys():
        b, a = before[key], after[key]
        if _decided(b["decision"]) != _decided(a["decision"]) or b["positions_m"].keys() != a["positions_m"].keys():
            changed.append({"frame": key, "before": b["decision"], "after": a["decision"]})
            continue
        if b["decision"] != a["decision"]:
            guesses.append(key)
        moves.append((_max_move_mm(b["positions_m"], a["positions_m"]), key))
        for name in b["figures"].keys() & a["figures"].keys():
            numbers[name] = max(numbers.get(name, 0.0), abs(a["figures"][name] - b["figures"][name]))
    max_move_mm, worst = max(moves, default=(0.0, None))
    figures = {name: [base["figures"].get(name), now["figures"].get(name)]
               for name in sorted(base["figures"].keys() | now["figures"].keys())}
    missing, added = sorted(before.keys() - after.keys()), sorted(after.keys() - before.keys())
    return {"frames": len(after), "changed": sorted(changed, key=lambda c: c["frame"]), "missing": missing,
            "added": added, "max_move_mm": max_move_mm, "worst_frame": worst,
            "moved": sorted(key for move, key in moves if move > TOLERANCE_MM), "guesses_changed": sorted(guesses),
            "max_number_difference": numbers, "figures": figures,
            "wall_s": [base.get("wall_s"), now.get("wall_s")],
            "ok": not changed and not missing and not added and max_move_mm <= TOLERANCE_MM}


def compare_runs(base: dict, now: dict) -> dict:
    """Every case of `now` against `base` (a `save`d results.json), and the verdict. A case the baseline
    lacks (saved before the case existed, or without --real-leds-cache) or only it has is listed, not
    compared: its absence is no changed result."""
    cases = {name: compare_run(base["runs"][name], run) for name, run in now["runs"].items() if name in base["runs"]}
    not_in_baseline = sorted(now["runs"].keys() - base["runs"].keys())
    not_run = sorted(base["runs"].keys() - now["runs"].keys())
    return {"tolerance_mm": TOLERANCE_MM, "baseline": {k: base.get(k) for k in ("mode", "code")},
            "now": {k: now.get(k) for k in ("mode", "code")}, "cases": cases, "not_in_baseline": not_in_baseline,
            "not_run": not_run, "ok": bool(cases) and all(c["ok"] for c in cases.values())}


def compare(folder: Path, mode: str, workers: int | None, benches: list[str] | None = None,
            save_to: Path | None = None, saved: Path | None = None, real_leds_cache: Path | None = None) -> dict:
    """The cases run again against FOLDER's; with `save_to`, this run is saved there as well (`save`); with
    `saved`, that folder's saved run instead of running again."""
    base = json.loads((folder / RESULTS_FILE).read_text())
    if base["mode"] != mode:
        raise ValueError(f"{folder / RESULTS_FILE} holds the {base['mode']} cases: compare with"
                         f"{' --quick' if base['mode'] == 'quick' else 'out --quick'}")
    if saved is not None:
        now = json.loads((saved / RESULTS_FILE).read_text())
        now["runs"] = {name: run for name, run in now["runs"].items() if benches is None or run["bench"] in benches}
    else:
        now = save(save_to, mode, workers, benches, real_leds_cache)
    report = compare_runs(base, now)
    report["wall_s"] = now["wall_s"]
    return report


def _number(value) -> str:
    if value is None:
        return "-"
    return f"{value:.4f}" if isinstance(value, float) and math.isfinite(value) else str(value)


def format_comparison(report: dict, all_figures: bool = False) -> str:
    base, now = report["baseline"]["code"], report["now"]["code"]
    lines = [f"results now ({now['commit']}{', dirty' if now['dirty'] else ''}, server {now['server_tree']}) "
             f"against the baseline ({base['commit']}{', dirty' if base['dirty'] else ''}, server "
             f"{base['server_tree']}), {report['now']['mode']} cases; a position fails above "
             f"{report['tolerance_mm']} mm",
             f"{'case':<22} {'frames':>6} {'changed':>7} {'max move mm':>11} {'s then':>6} {'s now':>6}  verdict"]
    for name, case in report["cases"].items():
        verdict = "same" if case["ok"] else f"FAILED ({case['error']})" if "error" in case else "DIFFERENT"
        if case["missing"] or case["added"]:
            verdict += f" ({len(case['missing'])} frames missing, {len(case['added'])} added)"
        then_s, now_s = (f"{s:.0f}" if s is not None else "-" for s in case["wall_s"])
        lines.append(f"{name:<22} {case['frames']:6d} {len(case['changed']):7d} {case['max_move_mm']:11.3g} "
                     f"{then_s:>6} {now_s:>6}  {verdict}")
    for name, case in report["cases"].items():
        for change in case["changed"][:SHOWN_CHANGES]:
            lines.append(f"  {name} {change['frame']}: {json.dumps(change['before'])} -> {json.dumps(change['after'])}")
        if len(case["changed"]) > SHOWN_CHANGES:
            lines.append(f"  {name}: {len(case['changed']) - SHOWN_CHANGES} more changed frames (--json lists them)")
        if case["moved"]:
            lines.append(f"  {name}: {len(case['moved'])} frames moved by more than {report['tolerance_mm']} mm, "
                         f"the most {case['worst_frame']} ({case['max_move_mm']:.4f} mm): "
                         + ", ".join(case["moved"][:SHOWN_CHANGES]))
        if case["guesses_changed"]:
            lines.append(f"  {name}: {len(case['guesses_changed'])} unconfident VLC guesses changed (no ID decided "
                         f"before or after; not failing): " + ", ".join(case["guesses_changed"][:SHOWN_CHANGES]))
        for number, difference in case["max_number_difference"].items():
            if difference:
                lines.append(f"  {name}: per-frame '{number}' differs by up to {difference:.4g} (shown, not failing)")
    def same(a, b) -> bool:  # within FIGURE_EPSILON (an exact rewrite's rounding); NaN (nothing to average) is NaN
        if a is None or b is None:
            return a is b
        return abs(a - b) <= FIGURE_EPSILON or (math.isnan(a) and math.isnan(b))

    shown = identical = 0
    lines.append("summary figures, baseline -> now" + ("" if all_figures else " (those that differ)") + ":")
    for name, case in report["cases"].items():
        for figure, (then, now_value) in case["figures"].items():
            if same(then, now_value) and not all_figures:
                identical += 1
                continue
            shown += 1
            lines.append(f"  {name} {figure}: {_number(then)} -> {_number(now_value)}"
                         + (f" ({now_value - then:+.3g})" if isinstance(then, float) and isinstance(now_value, float)
                            else ""))
    if not all_figures:
        lines.append(f"  ({shown} differ by more than {FIGURE_EPSILON:g}, {identical} within it; --all-figures shows "
                     f"every one)")
    if report["not_in_baseline"]:
        lines.append("cases not in the baseline (run, not compared): " + ", ".join(report["not_in_baseline"]))
    if report.get("not_run"):
        lines.append("cases of the baseline not run now (not compared): " + ", ".join(report["not_run"]))
    lines.append(f"results {'unchanged' if report['ok'] else 'CHANGED'} ({report['wall_s']:.0f} s)")
    return "\n".join(lines)


def add_results_bench(benches) -> None:
    """`lumipose bench results save|compare DIR`."""
    from simulator.cli import add_bench_flags

    results = benches.add_parser("results", help="issue 30's results check: save the benches' per-frame outcomes, "
                                                  "or compare them with a saved baseline")
    results.add_argument("action", choices=["save", "compare"],
                         help="save: run the cases, write DIR; compare: run them, hold them against DIR "
                              "(exit 1 when a decision changed or a position moved more than 0.01 mm)")
    results.add_argument("folder", type=Path, metavar="DIR", help="the baseline's folder (results.json)")
    results.add_argument("--quick", action="store_true",
                         help="a few frames of each bench (minutes) instead of the docs' configurations (tens)")
    results.add_argument("--benches", nargs="+", choices=BENCHES, default=None, help="only these benches' cases")
    results.add_argument("--all-figures", action="store_true", help="compare: list every summary figure, not "
                                                                    "only those that differ")
    results.add_argument("--save-to", type=Path, default=None, metavar="OUT",
                         help="compare: also save this run into OUT, as save does (default: not saved)")
    results.add_argument("--saved", type=Path, default=None, metavar="OUT",
                         help="compare: OUT's saved run (save, or compare --save-to) against DIR, running nothing")
    results.add_argument("--real-leds-cache", type=Path, default=None, metavar="DIR",
                         help="Luxapose's real LED photos (bench real-leds) from DIR, fetched there when missing "
                              "(not shipped: without it their case is skipped)")
    add_bench_flags(results, seed=False)
    results.set_defaults(run=run_results_command)


def run_results_command(args) -> int:
    mode = "quick" if args.quick else "full"
    if args.action == "save":
        saved = save(args.folder, mode, args.workers, args.benches, args.real_leds_cache)
        frames = sum(len(run.get("frames", [])) for run in saved["runs"].values())
        failed = {name: run["error"] for name, run in saved["runs"].items() if "error" in run}
        if args.json:
            print(json.dumps({k: v for k, v in saved.items() if k != "runs"} | {"frames": frames, "failed": failed},
                             indent=2))
        else:
            print(f"saved {frames} frames of {len(saved['runs'])} cases ({mode}) into {args.folder / RESULTS_FILE} "
                  f"in {saved['wall_s']:.0f} s, code {saved['code']}"
                  + "".join(f"\n  {name} FAILED: {error}" for name, error in failed.items()))
        return 1 if failed else 0
    try:
        report = compare(args.folder, mode, args.workers, args.benches, args.save_to, args.saved,
                         args.real_leds_cache)
    except (OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(json.dumps(report, indent=2) if args.json else format_comparison(report, args.all_figures))
    return 0 if report["ok"] else 1


def main(argv: list[str] | None = None) -> int:
    """`python -m simulator.bench_results save|compare DIR [--quick]`, the same as `lumipose bench results`."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m simulator.bench_results")
    add_results_bench(parser.add_subparsers(dest="bench", required=True))
    args = parser.parse_args(["results", *(sys.argv[1:] if argv is None else argv)])
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
