"""`lumipose bench vlc` and `lumipose bench office`: tables on stdout (or --json), PNG figures."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from simulator.cli import add_bench_flags

DEFAULT_DISTANCES = [1.0, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0]


def add_vlc_benches(benches) -> None:
    vlc = benches.add_parser("vlc", help="VLC ID success against distance, single frame and combined (Fig. 16)")
    vlc.add_argument("--distances", type=float, nargs="+", default=DEFAULT_DISTANCES, help="camera to panel, metres")
    vlc.add_argument("--sides", type=float, nargs="+", default=[0.174],
                     help="panel sizes, metres: a square's side, a rectangle's long side, a circle's diameter")
    vlc.add_argument("--shape", choices=["square", "rect", "circle"], default="square",
                     help="panel shape (rect: --aspect x as wide as long)")
    vlc.add_argument("--aspect", type=float, default=0.25, help="a rect's short side over its long side")
    vlc.add_argument("--trials", type=int, default=100, help="per point")
    vlc.add_argument("--max-frames", type=int, default=12, help="ID frames combined at most")
    vlc.add_argument("--exposures", type=float, nargs="+", default=None,
                     help="exposure sweep (s) at the first distance instead of the distance sweep")
    vlc.add_argument("--map-ids", type=int, default=0,
                     help="give the decoder a map of this many IDs (default 0: no map, all 256 candidates); "
                          "--foreign-share of the panels are then not of the map, one bit from a map ID")
    vlc.add_argument("--foreign-share", type=float, default=0.5, help="--map-ids: share of foreign panels")
    vlc.add_argument("--cut", nargs="+", choices=["bottom", "side"], default=None,
                     help="instead: one ID frame of a 0.6 m panel cut by the bottom border or a side, read by the "
                          "room path (named, located), per --shares; at the first of --distances (default 1.2 m)")
    add_depth_flag(vlc)
    vlc.add_argument("--shares", type=float, nargs="+", default=None,
                     help="--cut: shares of the panel's rows (bottom) or columns (side) in view")
    add_bench_flags(vlc, figures="write the success against distance (vlc-distance.png, vlc-rect.png, "
                                 "vlc-circle.png; --cut: vlc-cut.png against share) into this folder "
                                 "(default: no figures)")
    vlc.set_defaults(run=_run_vlc)
    office = benches.add_parser("office", help="the paper's office walks with four coded beacons (Figs. 17-18)")
    office.add_argument("--walks", nargs="+", default=["zigzag", "spiral"], choices=["zigzag", "spiral"],
                        help="walks to run")
    office.add_argument("--pose-scale", type=float, default=None,
                        help="pose frames, of the Mi 8 front resolution (default: the scene's, 0.5)")
    office.add_argument("--id-frames", type=int, default=4, help="ID frames beside each pose frame")
    office.add_argument("--inset", type=float, default=0.0, help="walk this far inside the area, metres")
    office.add_argument("--limit", type=int, default=None, help="only the first N captures of each walk")
    add_depth_flag(office, several=False)
    add_bench_flags(office, figures="write one PNG per walk (office-zigzag.png, office-spiral.png) into this "
                                    "folder (default: no figures)")
    office.set_defaults(run=_run_office)


def add_depth_flag(parser, several: bool = True) -> None:
    """`--depth`: the LEDs' modulation depth, a 0 chip at 1 - depth of a 1 chip (0.7, the codec's default:
    never off; 1.0: off between chips, as OOK or full-depth PWM drivers do); several values: one run each
    (`depths`); one value: None when not given (the scene's). The default is read when the bench runs:
    building the command line imports no numpy."""
    text = ("LED modulation depth: a 0 chip is 1 - DEPTH of a 1 chip (0.7: never off, the default"
            + ("" if several else " of the scenes") + "; 1.0: fully off between chips)")
    if several:
        parser.add_argument("--depth", type=_depth, nargs="+", help=text + "; one run each")
    else:
        parser.add_argument("--depth", type=_depth, help=text)


def depths(args) -> list[float]:
    """The depths `--depth` asked for, one run each: the codec's default when none."""
    from server.vlc.codec import DEFAULT_DEPTH

    return args.depth or [DEFAULT_DEPTH]


def _depth(text: str) -> float:
    import argparse

    value = float(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"a depth is between 0 and 1, got {text}")
    return value


def _run_vlc(args) -> int:
    from simulator.bench_vlc import VlcConfig, plot_vlc, run_vlc
    from simulator.reports import print_figures

    if args.cut:
        return _run_cut(args)

    reports = []
    base = VlcConfig(trials=args.trials, max_frames=args.max_frames, seed=args.seed, shape=args.shape,
                     aspect=args.aspect, map_ids=args.map_ids, foreign_share=args.foreign_share)
    for depth in depths(args):
        if args.exposures:
            for side in args.sides:
                for exposure in args.exposures:
                    config = replace(base, distance_m=args.distances[0], side_m=side, exposure_s=exposure, depth=depth)
                    reports.append(run_vlc(config, args.workers))
        else:
            for side in args.sides:
                for distance in args.distances:
                    reports.append(run_vlc(replace(base, distance_m=distance, side_m=side, depth=depth), args.workers))
    figures = []
    if args.figures and not args.exposures:
        title = "ID success, 1/8000 s ID frames, 256 candidate IDs"
        figures.append(_figure_path(args.figures, _vlc_figure_name(args.shape, args.sides)))
        plot_vlc(reports, figures[0], title if args.shape == "square" else f"{title}, {args.shape}")
    if args.json:
        print(json.dumps({"vlc": reports, "figures": [str(f) for f in figures]}, indent=2, default=float))
        print_figures(figures, args.json)
        return 0
    print(f"{'shape':>6} {'side':>6} {'depth':>5} {'dist':>5} {'exposure':>9} {'chips/fr':>8} {'single':>7} "
          f"{'combined':>8} {'frames':>6} {'captures':>8} {'max':>4} {'wrong':>5}")
    for r in reports:
        s, c = r["single"], r["combined"]
        print(f"{r['shape']:>6} {r['side_m']:6.3f} {r['depth']:5.2f} {r['distance_m']:5.2f} {r['exposure_s']:9.2e} "
              f"{s['chips_per_frame']:8.1f} {s['success_pct']:6.1f}% {c['success_pct']:7.1f}% {c['mean_frames']:6.2f} "
              f"{c['mean_captures']:8.2f} {c['max_frames_used']:4d} {s['confident_wrong'] + c['confident_wrong']:5d}")
        if "map" in c:
            m = c["map"]
            print(f"{'':>6} map of {r['map_ids']} IDs, combined: read {m['read_pct']:.1f}% of {m['map_trials']}, "
                  f"named wrong {m['named_wrong']}, foreign confident {m['foreign_confident']} "
                  f"of {m['foreign_trials']} foreign")
    print_figures(figures, args.json)
    return 0


def _vlc_figure_name(shape: str, sides: list[float]) -> str:
    """vlc-distance.png for the paper's 0.174 m square, vlc-distance-0.6m.png for others, vlc-rect.png ..."""
    if shape != "square":
        return f"vlc-{shape}.png"
    return "vlc-distance.png" if sides == [0.174] else "vlc-distance-" + "-".join(f"{s:g}m" for s in sides) + ".png"


def _figure_path(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    return folder / name


def _run_cut(args) -> int:
    from simulator.bench_vlc import CutConfig, plot_cut, run_cut
    from simulator.reports import print_figures

    distance = args.distances[0] if args.distances != DEFAULT_DISTANCES else 1.2
    reports = []
    for edge in args.cut:
        shares = args.shares or ([0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9] if edge == "bottom" else [0.2, 0.4, 0.6])
        for share in shares:
            for depth in depths(args):
                config = CutConfig(share=share, edge=edge, distance_m=distance, trials=args.trials, seed=args.seed,
                                   depth=depth)
                reports.append(run_cut(config, args.workers))
    figures = []
    if args.figures:
        figures.append(_figure_path(args.figures, "vlc-cut.png"))
        plot_cut(reports, figures[0])
    if args.json:
        print(json.dumps({"vlc_cut": reports, "figures": [str(f) for f in figures]}, indent=2, default=float))
        print_figures(figures, args.json)
        return 0
    print(f"{'edge':>6} {'share':>5} {'rows':>5} {'chips':>5} {'named':>6} {'wrong':>5} {'located':>7} {'mean mm':>7} "
          f"{'max mm':>6}  refusals")
    for r in reports:
        print(f"{r['edge']:>6} {r['share']:5.2f} {r['rows']:5.0f} {r['chips']:5.1f} {r['named_pct']:5.0f}% "
              f"{r['named_wrong']:5d} {r['located']:7d} {r['mean_mm']:7.1f} {r['max_mm']:6.1f}  {r['refusals']}")
    print_figures(figures, args.json)
    return 0


def _fmt(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def _run_office(args) -> int:
    from simulator.bench_office import OfficeConfig, plot_walk, run_office
    from simulator.reports import print_figures

    config = OfficeConfig(pose_scale=args.pose_scale, id_frames=args.id_frames, inset_m=args.inset,
                          max_captures=args.limit, seed=args.seed, depth=args.depth)
    reports = run_office(config, tuple(args.walks), args.workers)
    figures = []
    for report in reports if args.figures else []:
        figures.append(_figure_path(args.figures, f"office-{report['config']['walk']}.png"))
        plot_walk(report, figures[-1])
    if args.json:
        print(json.dumps({"office": [{k: r[k] for k in ("config", "summary", "stats")} for r in reports],
                          "figures": [str(f) for f in figures]}, indent=2))
        print_figures(figures, args.json)
        return 0
    print(f"{'walk':>7} {'captures':>8} {'cover':>6} {'mean':>6} {'p95':>6} {'max':>6} {'filt.mean':>9} "
          f"{'ID err':>6} {'vlc':>4} {'carried':>7} {'outl':>4} {'trans.cover':>11} {'trans.mean':>10}  (2D, mm)")
    for r in reports:
        s = r["summary"]
        print(f"{r['config']['walk']:>7} {s['captures']:8d} {s['coverage_pct']:5.1f}% {_fmt(s['fixes']['mean_mm']):>6} "
              f"{_fmt(s['fixes']['p95_mm']):>6} {_fmt(s['fixes']['max_mm']):>6} {_fmt(s['filtered']['mean_mm']):>9} "
              f"{s['id_errors']:6d} {s['ids_by_vlc']:4d} {s['ids_carried']:7d} {s['outliers']:4d} "
              f"{s['transition_coverage_pct']:10.1f}% {_fmt(s['transition_fixes']['mean_mm']):>10}")
        print(f"{'':>7} refusals: {s['refusals']}")
    print_figures(figures, args.json)
    return 0
