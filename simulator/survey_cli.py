"""`lumipose bench survey`: a table on stdout (or --json); `--fixtures DIR` also writes the frames."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from simulator.cli import add_bench_flags

from shared_schemas.cli import plural


def add_survey_bench(benches) -> None:
    bench = benches.add_parser("survey",
                               help="beacon survey of an office of 4 or 9 panels against the truth (issue 14)")
    bench.add_argument("--panels", type=int, nargs="+", default=[4, 9], choices=[4, 9],
                       help="offices to survey, by panel count")
    bench.add_argument("--frames", type=int, default=40, help="survey frames per office")
    bench.add_argument("--scale", type=float, default=None, help="of the Mi 8 front resolution (default: 0.5)")
    bench.add_argument("--walk", choices=["zigzag", "spiral", "none"], default="zigzag",
                       help="the office walk positioned with the surveyed and the true map (none: skip)")
    bench.add_argument("--luminance-spread", type=float, default=0.0,
                       help="panels' luminances spread evenly over +- this share (0.15: +-15 %%); the walk keeps the scene's")
    bench.add_argument("--walk-limit", type=int, default=None, help="only the first N captures of the walk")
    bench.add_argument("--fixtures", type=Path, default=None,
                       help="also write each office's frames, labels.json and sketch.json into DIR/SCENE (for `lumipose "
                            "survey`; `lumipose simulate SCENE OUT --survey N` writes one set without the bench)")
    add_bench_flags(bench, workers=False)
    bench.set_defaults(run=_run_survey_bench)

    bearing = benches.add_parser("survey-bearing",
                                 help="the survey's compass bearing over many seeds: its error against its sigma")
    bearing.add_argument("--seeds", type=int, default=40, help="surveys, of seeds --seed, --seed + 1, ...")
    bearing.add_argument("--panels", type=int, default=4, choices=[4, 9], help="the office, by panel count")
    bearing.add_argument("--frames", type=int, default=12, help="survey frames per survey")
    bearing.add_argument("--scale", type=float, default=0.25, help="of the Mi 8 front resolution")
    add_bench_flags(bearing, workers=False)
    bearing.set_defaults(run=_run_bearing_bench)


def write_survey_inputs(scene, out: Path, frames: int) -> int:
    """`lumipose simulate SCENE OUT --survey FRAMES`: what `lumipose survey` reads, as the app uploads it."""
    import numpy as np

    from simulator.survey import survey_set, write_survey_fixtures

    truth, sketch, anchor, shots = survey_set(scene, frames, np.random.default_rng(scene.seed))
    paths, labels, sketch_path = write_survey_fixtures(out, shots, sketch, out / "frames")
    (out / "map.json").write_text(truth.model_dump_json(by_alias=True, indent=2) + "\n")
    named = sum(len(shot.labels) for shot in shots)
    print(f"wrote {plural(len(paths), 'survey frame')} into {paths[0].parent} ({paths[0].name} ... {paths[-1].name}), "
          f"{labels} ({plural(named, 'panel label')}), {sketch_path} (the panels a few cm off; anchor: beacon "
          f"{anchor}) and {out / 'map.json'} (the truth)")
    return 0


def _fmt(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def _print(report: dict) -> None:
    luminances = ", ".join(f"{k} {v:.0f}" for k, v in report["panel_luminance_nits"].items())
    print(f"panel luminances (cd/m2): {luminances}")
    print(f"{report['scene']}: {report['frames_used']} of {report['frames']} frames used, "
          f"RMS {report['rms_px']:.3f} px, "
          f"survey {report['survey_s']:.1f} s")
    print(f"{'beacon':>6} {'frames':>6} {'centre err':>10} {'err x/y/z (mm)':>22} {'sigma x/y/z (mm)':>18} "
          f"{'yaw err':>8} {'sigma':>6}")
    for p in report["panels"]:
        ex, ey, ez = p["centre_error_xyz_mm"]
        sx, sy, sz = p["centre_sigma_xyz_mm"]
        note = "  (anchor)" if p["anchor"] else ""
        print(f"{p['beacon_id']:>6} {p['frames']:>6} {p['centre_error_mm']:8.2f}mm {ex:+7.2f} {ey:+7.2f} {ez:+7.2f} "
              f"{sx:6.2f} {sy:5.2f} {sz:5.2f} {p['yaw_error_deg']:+8.3f} {p['yaw_sigma_deg']:6.3f}{note}")
    met = report["max_centre_error_mm"] <= report["targets"]["centre_mm"] and \
        report["max_yaw_error_deg"] <= report["targets"]["yaw_deg"]
    print(f"worst     centre {report['max_centre_error_mm']:.2f} mm (target 2), "
          f"yaw {report['max_yaw_error_deg']:.3f} deg "
          f"(target 0.1): {'met' if met else 'NOT met'}")
    print(f"bearing   {_fmt(report['bearing_deg'])} deg +- {_fmt(report['bearing_sigma_deg'])}, error "
          f"{_fmt(report['bearing_error_deg'])} deg")
    for s in report["skipped"]:
        print(f"skipped   {s['name']}: {s['why']}")
    walk = report.get("walk")
    if walk:
        print(f"walk      {walk['walk']} (2D error of the raw fixes, mm)")
        for label in ("surveyed_map", "true_map"):
            s = walk[label]
            f = s["fixes"]
            print(f"  {label:>13}: {plural(s['captures'], 'capture')}, cover {s['coverage_pct']:.1f} %, "
                  f"mean {_fmt(f['mean_mm'])}, "
                  f"p95 {_fmt(f['p95_mm'])}, max {_fmt(f['max_mm'])}, ID errors {s['id_errors']}")


def _run_survey_bench(args) -> int:
    from simulator.bench_survey import SurveyBenchConfig, run_survey_bench

    base = SurveyBenchConfig(frames=args.frames, scale=args.scale, seed=args.seed,
                             walk=None if args.walk == "none" else args.walk, walk_limit=args.walk_limit,
                             luminance_spread=args.luminance_spread)
    reports = []
    for panels in args.panels:
        reports.append(run_survey_bench(replace(base, panels=panels), args.fixtures))
    if args.json:
        print(json.dumps({"survey": reports}, indent=2))
        return 0
    for report in reports:
        _print(report)
    return 0


def _run_bearing_bench(args) -> int:
    from simulator.bench_survey import SurveyBenchConfig, run_bearing_bench

    config = SurveyBenchConfig(panels=args.panels, frames=args.frames, scale=args.scale, seed=args.seed, walk=None)
    report = run_bearing_bench(config, args.seeds)
    if args.json:
        print(json.dumps({"survey_bearing": report}, indent=2))
        return 0
    print(f"{'seed':>4} {'frames':>6} {'bearing':>8} {'sigma':>6} {'error':>6} {'error/sigma':>11}")
    for run in report["runs"]:
        print(f"{run['seed']:>4} {run['frames_used']:>6} {run['bearing_deg']:8.1f} {run['sigma_deg']:6.1f} "
              f"{run['error_deg']:+6.1f} {run['error_over_sigma']:+11.2f}")
    for refused in report["refused"]:
        print(f"{refused['seed']:>4} refused: {refused['why']}")
    within = report["within_sigma_pct"]
    print(f"within    1 / 2 / 3 sigma: {within['1']:.0f} / {within['2']:.0f} / {within['3']:.0f} % of "
          f"{plural(len(report['runs']), 'survey')} (a sigma that holds: 68 / 95 / 99.7); RMS error/sigma "
          f"{report['rms_error_over_sigma']:.2f}, RMS error {report['rms_error_deg']:.1f} deg, mean sigma "
          f"{report['mean_sigma_deg']:.1f} deg")
    return 0
