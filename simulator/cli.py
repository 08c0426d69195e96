"""Simulator subcommands of `lumipose`: `render`, `simulate` and `bench ...`, and the figures of
`lumipose client samples evaluate --figures` (`plot_sample_evaluation`)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from shared_schemas import DEMO_MAP_NAME, device_profiles
from shared_schemas.cli import BadInput, describe_file_error, plural, read_map_argument, report_bad_input

# simulator.bench_robustness.GROUPS, without importing the renderer for every `lumipose --help`
# every command that draws: `--figures DIR`, no figures unless asked; the data drawn from goes beside them
FIGURES_HELP = "write {pngs} into this folder, with {data} beside them (default: no figures, nothing written)"

ROBUSTNESS_GROUPS = ("reference", "defocus", "glare", "binning", "demosaic", "noise", "sharpen", "tone", "jpeg",
                     "motion", "panel", "phone")
# simulator.bench_speed.PATHS, likewise without importing it
SPEED_PATHS = ("square", "square-quarter", "cut", "rectangle", "circle", "id-frame", "first-capture", "service-full",
               "service-window")


def add_bench_flags(parser, *, seed: int | None | bool = 1, workers: bool = True, figures: str | None = None) -> None:
    """The flags the benches share, meaning the same on each: `--seed` (an int default, None: the scene file's,
    False: none), `--workers`, `--figures DIR` (its help says what is drawn) and `--json`."""
    if seed is not False:
        parser.add_argument("--seed", type=int, default=seed,
                            help="random seed" + (" (default: the scene file's)" if seed is None else ""))
    if workers:
        parser.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    if figures is not None:
        parser.add_argument("--figures", type=Path, default=None, metavar="DIR", help=figures)
    parser.add_argument("--json", action="store_true", help="print the report as JSON on stdout")


def add_commands(commands) -> None:
    render = commands.add_parser("render", help="render a fixture (NAME.y + NAME.json) for a given pose")
    render.add_argument("out", type=Path, help="output stem, e.g. out/frame1")
    render.add_argument("--profile", default="xiaomi-mi8-front", choices=sorted(device_profiles()),
                        help="bundled device profile of the camera")
    render.add_argument("--scale", type=float, default=1.0, help="of the profile's native resolution")
    render.add_argument("--map", default=DEMO_MAP_NAME, help="a map file, or a bundled map's name")
    render.add_argument("--beacon-id", type=int, default=None, help="default: the map's first beacon")
    render.add_argument("--position", type=float, nargs=3, default=[0.0, 0.0, 0.0], metavar=("X", "Y", "Z"),
                        help="camera position in the map, metres")
    render.add_argument("--ypr", type=float, nargs=3, default=[0.0, 0.0, 0.0], metavar=("YAW", "PITCH", "ROLL"),
                        help="camera attitude in degrees, R_wc = Rz(yaw) Ry(pitch) Rx(roll)")
    render.add_argument("--psf", type=float, default=1.0, help="PSF sigma, pixels")
    render.add_argument("--overexposure", type=float, default=4.0, help="panel level / saturation")
    render.add_argument("--seed", type=int, default=0, help="sensor noise seed")
    render.add_argument("--no-gravity", action="store_true", help="leave gravity_camera out of the JSON")
    render.add_argument(
        "--png", action="store_true", help="also write OUT.png: the same pixels, to view (and locate: `locate OUT.png`)"
    )
    render.set_defaults(run=_run_render)

    simulate = commands.add_parser("simulate", help="render a scene's series (or one pose) into fixture files")
    simulate.add_argument("scene", help="scene file, or a bundled scene: " + ", ".join(_bundled_scenes()))
    simulate.add_argument("out", type=Path, help="output folder (fixtures, scene.json, map.json)")
    simulate.add_argument("--pose", type=float, nargs=3, default=None, metavar=("X", "Y", "Z"),
                          help="one sample at this camera position instead of the scene's series")
    simulate.add_argument("--ypr", type=float, nargs=3, default=[0.0, 0.0, 0.0], metavar=("YAW", "PITCH", "ROLL"),
                          help="with --pose: camera attitude in degrees")
    simulate.add_argument("--limit", type=int, default=None, help="only the first N samples of the series")
    simulate.add_argument("--scale", type=float, default=None, help="override the camera's resolution scale")
    simulate.add_argument("--seed", type=int, default=None, help="override the scene's seed")
    simulate.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    simulate.add_argument("--bursts", action="store_true",
                          help="each sample as the app captures it: a pose frame, then ID frames (NAME_0000_0_pose, "
                               "NAME_0000_1_id, ...; the scene's id_frames settings)")
    simulate.add_argument("--survey", type=int, default=None, metavar="FRAMES",
                          help="instead: FRAMES survey frames as the app's 'Survey room' screen takes them, for "
                               "`lumipose survey` (frames/, labels.json, sketch.json, map.json: the truth)")
    simulate.set_defaults(run=_run_simulate)

    bench = commands.add_parser("bench", help="benchmarks that print figures")
    benches = bench.add_subparsers(dest="bench", required=True)
    accuracy = benches.add_parser("accuracy", help="position error over rendered test-bench frames")
    accuracy.add_argument("--distances", type=float, nargs="+", default=[1.0, 2.0, 3.0],
                          help="camera to beacon, metres")
    accuracy.add_argument("--frames", type=int, default=None, help="per distance (200); with --shape, per shape (100)")
    accuracy.add_argument("--scale", type=float, default=1.0, help="of the Mi 8 front camera's native resolution")
    accuracy.add_argument("--max-tilt", type=float, default=10.0, help="largest random camera tilt, degrees")
    accuracy.add_argument("--gravity-sigma", type=float, default=0.1, help="gravity sensor error, degrees")
    add_bench_flags(accuracy)
    accuracy.add_argument("--renderer", choices=["ours", "blender", "both"], default="ours",
                          help="blender: Cycles' radiance through the same sensor (needs bpy); both: the same frames "
                               "from each, and the ratio of their mean errors")
    accuracy.add_argument("--chain", choices=["none", "phone"], default="none",
                          help="phone: the frames through a phone's chain, focused 25 %% too near, sharpened (0.8) and "
                               "JPEG 90 (bench robustness's 'phone still'; either renderer)")
    accuracy.add_argument("--shape", action="store_true",
                          help="instead of the distance table, the panel-shape table (issue 11: 600 x 600 mm, "
                               "1200 x 300 mm, a 0.2 m circle with heading and the paper's square, all 1.4 m up)")
    accuracy.set_defaults(run=_run_accuracy)
    partial = benches.add_parser("partial", help="panels cut by the image border: coverage and error by visible share")
    partial.add_argument("--distances", type=float, nargs="+", default=[1.0, 2.0, 3.0], help="camera to beacon, metres")
    partial.add_argument("--frames", type=int, default=40, help="per distance and resolution")
    partial.add_argument("--scales", type=float, nargs="+", default=[1.0, 0.25],
                         help="of the Mi 8 front camera's native resolution (0.25: 970 x 1296)")
    add_bench_flags(partial, figures="write partial.png (error against visible share) here, with partial.json "
                                     "beside it (default: no figures)")
    partial.set_defaults(run=_run_partial)
    negatives = benches.add_parser("negatives", help="frames the map does not describe: wrong maps on rendered "
                                   "frames, real photos of rooms and lamps (every fix of those is wrong)")
    negatives.add_argument("--frames", type=int, default=20, help="rendered frames per wrong map")
    negatives.add_argument("--scale", type=float, default=0.25, help="of the profile's native resolution")
    negatives.add_argument("--required-sigma", type=float, default=0.01,
                           help="the wrong maps' required_sigma_m, metres")
    negatives.add_argument("--sigmas", type=float, nargs="+", default=[0.01, 0.05, 0.1, 0.5, 1.0],
                           help="required_sigma_m of the real photos' maps, metres")
    negatives.add_argument("--local", type=Path,
                           help="a folder with the manifest's photos that are not shipped (default: none)")
    negatives.add_argument("--no-photos", action="store_true", help="only the wrong maps")
    add_bench_flags(negatives)
    negatives.set_defaults(run=_run_negatives)
    robustness = benches.add_parser("robustness", help="what each stage of a phone's image chain costs (issue 13)")
    robustness.add_argument("--distances", type=float, nargs="+", default=[1.0, 2.0], help="camera to beacon, metres")
    robustness.add_argument("--scales", type=float, nargs="+", default=[0.25, 1.0],
                            help="of the Mi 8 front camera's native resolution (0.25: 970 x 1296)")
    robustness.add_argument("--frames", type=int, default=40, help="per cell (effect x distance x scale)")
    robustness.add_argument("--effects", nargs="+", default=list(ROBUSTNESS_GROUPS), metavar="GROUP",
                            help="effect groups: " + ", ".join(ROBUSTNESS_GROUPS[1:]) + " (the references no chain, "
                                 "ISP off and ISP on always run)")
    add_bench_flags(robustness)
    robustness.set_defaults(run=_run_robustness)
    speed = benches.add_parser("speed", help="every path's time as a ratio to one cv2.threshold pass (issue 30)",
                               description="Every path of issue 30's table (simulator/bench_speed.py) against one "
                                           "cv2.threshold pass over a full frame timed just before each call; "
                                           "medians over the frames and rounds, beside each path's target.")
    speed.add_argument("--path", nargs="+", default=["all"], choices=[*SPEED_PATHS, "all"], metavar="PATH",
                       help="paths to measure: " + ", ".join(SPEED_PATHS) + " or all (default)")
    speed.add_argument("--frames", type=int, default=3,
                       help="frames per distance (square, cut); the other paths take as many at their one distance")
    speed.add_argument("--rounds", type=int, default=5, help="passes over all the frames")
    speed.add_argument("--repeats", type=int, default=1, help="timed calls of each frame per round")
    speed.add_argument("--distance", type=float, nargs="+", default=[1.0, 2.0, 3.0],
                       help="camera to beacon, metres (square, cut; the ID paths take the first)")
    speed.add_argument("--no-gravity", action="store_true", help="leave the gravity vector out (no MAP pose fit)")
    speed.add_argument("--report", type=Path, default=None, metavar="JSON",
                       help="instead of measuring: the report of an earlier `bench speed --json`")
    speed.add_argument("--baseline", type=Path, default=None, metavar="JSON",
                       help="a `bench speed --json` report at the commit before: the table's and figure's before")
    speed.add_argument("--markdown", action="store_true",
                       help="print issue 30's table (path, before, target, after) in Markdown")
    add_bench_flags(speed, seed=1, workers=False, figures=FIGURES_HELP.format(pngs="speed.png", data="speed.json"))
    speed.set_defaults(run=_run_speed)
    load = benches.add_parser("load", help="the HTTP service under concurrent clients (over 3 minutes by default)",
                              description="The HTTP service under concurrent clients (its own server, or --url). One "
                                          "run per frame kind, client count and encoding: the defaults take over 3 "
                                          "minutes (9 runs of 20 s).")
    load.add_argument("--frames", nargs="+", choices=["1080p", "full", "full-window"],  # bench_service.FRAME_WIDTHS
                      default=["1080p", "full", "full-window"],
                      help="full-window: the full frame cut to the beacon's window by the client")
    load.add_argument("--clients", type=int, nargs="+", default=[1, 2, 4], help="concurrent clients, one run each")
    load.add_argument("--seconds", type=float, default=20.0,
                      help="per run, one per frame x client count x encoding (default: 20; with the other defaults "
                           "9 runs, over 3 minutes)")
    load.add_argument("--encodings", nargs="+", choices=["none", "gzip", "zstd"], default=["none"],
                      help="upload compression, one run each")
    load.add_argument("--workers", type=int, default=1, help="uvicorn worker processes")
    load.add_argument("--url",
                      help="load-test the running service there (e.g. the nginx replicas) instead of starting one; "
                           "no server-side figures then (default: our own server)")
    load.add_argument("--devices", action="store_true",
                      help="client n sends X-Lumipose-Device: load-<n>, as phones do: the live board records every "
                           "frame and keeps its picture's source (default: no device header)")
    load.add_argument("--watchers", type=int, default=0,
                      help="open operator pages: subscribers that read /v1/live/events through each run")
    load.add_argument("--picture-every-s", type=float, default=2.0,
                      help="with --devices and --watchers: one watcher fetches device load-0's newest kept picture "
                           "this often, as the page's frame view; 0: none")
    load.add_argument("--live-frames", type=int,
                      help="the started server's serve --live-frames (pictures kept per device; 0: none) "
                           "(default: the server's, 3)")
    load.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    load.set_defaults(run=_run_load)
    replicas = benches.add_parser("replicas", help="bench load through nginx to 1, 2, 3 replicas sharing Redis; "
                                                   "Redis against memory; bytes per device (minutes)",
                                  description="Starts redis-server, the replicas (lumipose serve --redis) and nginx "
                                              "(docker/nginx.conf) on 127.0.0.1 itself; needs Debian's redis-server "
                                              "and nginx. One run per replica count, frame kind and client count, "
                                              "then one replica straight with and without Redis.")
    replicas.add_argument("--replicas", type=int, nargs="+", default=[1, 2, 3], help="replica counts, one set of "
                                                                                    "runs each")
    replicas.add_argument("--frames", nargs="+", choices=["1080p", "full", "full-window"],
                          default=["1080p", "full-window"], help="frame kinds, as bench load's")
    replicas.add_argument("--clients", type=int, nargs="+", default=[1, 2, 4], help="concurrent clients, one run each")
    replicas.add_argument("--seconds", type=float, default=10.0, help="per run")
    replicas.add_argument("--json", action="store_true", help="print the report as JSON on stdout")
    replicas.set_defaults(run=_run_replicas)
    for name, help_text in (("grid", "the paper's simulated 391-point grid (Table 1, Figs. 11-12)"),
                            ("bench-real", "the grid as the paper's real bench saw it (Table 2, Figs. 13-14)")):
        grid = benches.add_parser(name, help=help_text)
        add_bench_flags(grid, seed=None, figures=FIGURES_HELP.format(
            pngs="the scatter and heat map", data="report.json, outcomes.json and scene.json"))
        grid.add_argument("--scale", type=float, default=1.0, help="of the Mi 8 front camera's native resolution")
        grid.add_argument("--limit", type=int, default=None, help="only about N evenly spread grid points")
        if name == "bench-real":
            grid.add_argument("--uncalibrated", action="store_true",
                              help="the pipeline assumes the datasheet pinhole without distortion, as the paper's")
            grid.add_argument("--profile", type=Path, default=None,
                              help="the pipeline uses this calibrated profile (e.g. from `lumipose bench calibration "
                                   "--lens bench-real --out profile.json`)")
        else:
            grid.add_argument("--scene", default=None,
                              help="locate the series of this scene file instead (its own resolution; --scale ignored)")
            grid.add_argument("--yaw-jitter", type=float, default=0.0,
                              help="random phone yaw within +-this many degrees (0: exactly face to face, the paper's)")
        grid.set_defaults(run=_run_grid_bench, bench_name=name)
    distance = benches.add_parser("distance", help="2D error from 1 m to 3 m (5 x 5 points over the FOV each)")
    distance.add_argument("--distances", type=float, nargs="+", default=None,
                          help="metres (default: 1.0 to 3.0 by 0.1)")
    distance.add_argument("--yaw-jitter", type=float, default=0.0,
                          help="random phone yaw within +-this many degrees (0: exactly face to face)")
    tilt = benches.add_parser("tilt", help="2D error against camera tilt at 1 m")
    tilt.add_argument("--tilts", type=float, nargs="+", default=None, help="degrees (default: 0 to 15 by 2.5)")
    for sweep, name in ((distance, "distance"), (tilt, "tilt")):
        add_bench_flags(sweep, seed=None, figures=FIGURES_HELP.format(pngs=f"{name}-sweep.png", data="report.json"))
        sweep.add_argument("--scale", type=float, default=1.0, help="of the Mi 8 front camera's native resolution")
        sweep.set_defaults(run=_run_sweep, bench_name=name)
    calibration = benches.add_parser("calibration", help="camera calibration on rendered ChArUco photos (issue 14)")
    calibration.add_argument("--views", type=int, default=20, help="photos per set")
    calibration.add_argument("--scale", type=float, default=1.0, help="of the Mi 8 front camera's native resolution")
    calibration.add_argument("--lens", choices=["phone", "phone-k3", "bench-real"], default="phone",
                             help="phone: a phone-like Mi 8 front lens (k3 0); phone-k3: the same with k3 0.002; "
                                  "bench-real: `bench bench-real`'s lens")
    calibration.add_argument("--corner-views", type=int, default=None,
                             help="views of the good set reaching into the image's corners, the rest spread "
                                  "(default 12: three per corner)")
    calibration.add_argument("--no-poor-sets", action="store_true", help="skip the frontal and corner-only sets")
    calibration.add_argument("--out", type=Path, default=None, help="write the calibrated profile here")
    add_bench_flags(calibration, workers=False)
    calibration.set_defaults(run=_run_calibration_bench)
    boards = benches.add_parser("boards", help="boards users already own, on real public photos (issue 29)")
    boards.add_argument("--videos", type=Path, default=None,
                        help="a folder with caliscope's cam_*.mp4: every frame instead of the shipped ones")
    add_bench_flags(boards, seed=False, workers=False)
    boards.set_defaults(run=_run_boards_bench)
    real_leds = benches.add_parser("real-leds", help="Luxapose's phone photos of LEDs keyed fully off, fetched "
                                                     "from lab11/vlc-localization (issue 29)")
    real_leds.add_argument("--cache", type=Path, default=Path("~/.cache/lumipose/lab11"),
                           help="where the fetched photos are kept (default ~/.cache/lumipose/lab11)")
    add_bench_flags(real_leds, seed=False, workers=False)
    real_leds.set_defaults(run=_run_real_leds_bench)
    fidelity = benches.add_parser("fidelity", help="top-side ratio, our renderer / exact projection (Fig. 10)")
    fidelity.add_argument("--distances", type=float, nargs="+", default=None,
                          help="metres (default: 1.0 to 3.0 by 0.1)")
    fidelity.add_argument("--blender", action="store_true", help="also render each view with Blender (needs bpy)")
    add_bench_flags(fidelity, seed=False, workers=False,
                    figures=FIGURES_HELP.format(pngs="fidelity.png", data="report.json"))
    fidelity.set_defaults(run=_run_fidelity)
    render_speed = benches.add_parser("render", help="time to render one full-resolution frame of a scene")
    render_speed.add_argument("--scene", default="paper-bench", help="a scene file or a bundled scene")
    render_speed.add_argument("--repeats", type=int, default=10, help="timed renders")
    add_bench_flags(render_speed, seed=False, workers=False)
    render_speed.set_defaults(run=_run_render_speed)
    from simulator.vlc_cli import add_vlc_benches  # `bench vlc` and `bench office` (issue 4)

    add_vlc_benches(benches)
    from simulator.survey_cli import add_survey_bench  # `bench survey` (issue 14)

    add_survey_bench(benches)
    from simulator.bench_results import add_results_bench  # `bench results` (issue 30: results unchanged)

    add_results_bench(benches)


def plot_sample_evaluation(report, folder: Path, cell_m: float) -> list[Path]:
    """The paper's Figs. 13-14 (scatter, heat map) of the service's sample evaluation (a
    shared_schemas.api.Evaluation): `lumipose client samples evaluate --figures DIR`; heat-map cells of
    `cell_m` (the `--cell` the 'i,j' labels were read with), cells without a sample shown as not run."""
    from simulator.reports import Outcome, plot_heatmap, plot_scatter

    outcomes = [Outcome(index=i, label=row.label or row.id, true_m=tuple(row.truth_m),
                        estimate_m=tuple(row.position_m) if row.ok else None, reason=row.reason, message=None,
                        reprojection_px=None)
                for i, row in enumerate(report.rows) if row.truth_m is not None]
    if not outcomes:
        raise ValueError("no stored sample has a truth (ground_truth or an 'i,j' label) to plot")
    folder.mkdir(parents=True, exist_ok=True)
    scatter, heatmap = folder / "samples_scatter.png", folder / "samples_heatmap.png"
    plot_scatter(outcomes, scatter, f"stored samples, map {report.map}")
    plot_heatmap(outcomes, heatmap, f"2D error, map {report.map}", cell_m)
    return [scatter, heatmap]


def _run_render(args) -> int:
    import numpy as np

    from server.camera import intrinsics_from_profile
    from server.geometry import rotation_from_ypr
    from simulator.fixtures import fixture_meta, write_fixture
    from simulator.render import CameraPose, SensorModel, render_frame

    try:
        beacon_map = read_map_argument(args.map)
    except BadInput as problem:
        return report_bad_input(problem)
    beacon = beacon_map.beacon(args.beacon_id) if args.beacon_id is not None else beacon_map.beacons[0]
    if beacon is None:
        return report_bad_input(BadInput(f"beacon {args.beacon_id} is not in {args.map}", field="beacon_id"))
    profile = device_profiles()[args.profile]
    width, height = round(profile.width * args.scale), round(profile.height * args.scale)
    camera = intrinsics_from_profile(profile, width, height)
    pose = CameraPose(position_m=np.array(args.position), rotation_wc=rotation_from_ypr(*args.ypr))
    sensor = SensorModel(psf_sigma_px=args.psf, plateau_dn=255.0 * args.overexposure)
    try:
        pixels = render_frame(beacon, camera, pose, width, height, sensor, np.random.default_rng(args.seed))
    except ValueError as error:
        return report_bad_input(BadInput(str(error)))
    gravity = None if args.no_gravity else (pose.rotation_wc.T @ [0.0, 0.0, -1.0]).tolist()
    raw, meta = write_fixture(args.out, pixels, fixture_meta(camera, width, height, pose, gravity_camera=gravity))
    print(f"wrote {raw} and {meta}")
    if args.png:
        import cv2

        png = raw.with_suffix(".png")
        png.write_bytes(cv2.imencode(".png", pixels)[1].tobytes())  # 8-bit grey, lossless: the frame's own pixels
        print(f"wrote {png}")
    return 0


def _bundled_scenes() -> list[str]:
    # simulator.scene.SCENES_DIR, without importing the renderer for every `lumipose --help`
    return sorted(path.stem for path in (Path(__file__).parent / "scenes").glob("*.json"))


def _run_simulate(args) -> int:
    from pydantic import ValidationError

    from simulator.sampling import series_poses, write_series
    from simulator.scene import PoseSpec, PosesSeries, SeriesSpec, find_scene

    try:
        scene = find_scene(args.scene)
        updates = {}
        if args.seed is not None:
            updates["seed"] = args.seed
        if args.scale is not None:
            updates["camera"] = scene.camera.model_copy(update={"scale": args.scale})
            if scene.id_frames.scale is not None:  # the ID frames keep their size relative to the pose frames
                ratio = args.scale / scene.camera.scale
                updates["id_frames"] = scene.id_frames.model_copy(update={"scale": scene.id_frames.scale * ratio})
        scene = scene.model_validate(scene.model_copy(update=updates).model_dump(by_alias=True))
        if args.survey is not None:
            from simulator.survey_cli import write_survey_inputs

            return write_survey_inputs(scene, args.out, args.survey)
        if args.pose is not None:
            series = SeriesSpec(path=PosesSeries(poses=[PoseSpec(position_m=args.pose, ypr_deg=args.ypr)]))
            scene = scene.model_copy(update={"series": series})
        elif args.limit is not None:
            # the drawn attitudes become explicit poses, so scene.json reproduces exactly these samples
            poses = [PoseSpec(position_m=list(p.position_m), ypr_deg=list(p.ypr_deg), t_s=p.t_s,
                              velocity_mps=list(p.velocity_mps), angular_velocity_dps=list(p.angular_velocity_dps))
                     for p in series_poses(scene)[: max(args.limit, 1)]]
            scene = scene.model_copy(update={"series": SeriesSpec(path=PosesSeries(poses=poses))})
        stems = write_series(scene, args.out, args.workers, bursts=args.bursts)
    except (OSError, ValueError, ValidationError) as error:
        return report_bad_input(BadInput(str(error)))
    print(f"wrote {plural(len(stems), 'fixture')} ({stems[0]} ... {stems[-1]}), scene.json and map.json into {args.out}")
    return 0


def _run_load(args) -> int:
    from simulator.bench_service import run_load_command

    return run_load_command(args)


def _run_replicas(args) -> int:
    from simulator.bench_replicas import run_replicas_command

    return run_replicas_command(args)


def _run_accuracy(args) -> int:
    if args.shape:
        from simulator.bench_shapes import run_shapes_command

        return run_shapes_command(args)
    from simulator.bench_robustness import phone_chain
    from simulator.benchmarks import AccuracyConfig, renderer_ratios, run_accuracy

    reports = []
    frames = 200 if args.frames is None else args.frames
    renderers = ["ours", "blender"] if args.renderer == "both" else [args.renderer]
    for distance in args.distances:
        for renderer in renderers:
            config = AccuracyConfig(distance_m=distance, frames=frames, scale=args.scale, max_tilt_deg=args.max_tilt,
                                    gravity_sigma_deg=args.gravity_sigma, seed=args.seed, renderer=renderer,
                                    chain=phone_chain(distance) if args.chain == "phone" else None)
            reports.append(run_accuracy(config, args.workers))
    ratios = renderer_ratios(reports) if args.renderer == "both" else []
    if args.json:
        print(json.dumps({"accuracy": reports, "renderer_ratios": ratios} if ratios else {"accuracy": reports},
                         indent=2))
        return 0
    print(f"{'distance':>8} {'renderer':>8} {'mode':>8} {'mean':>7} {'std':>7} {'min':>7} {'max':>7} {'p95':>7} "
          f"{'cover':>6}  (2D, mm)")
    for report in reports:
        head = f"{report['distance_m']:>7.1f}m {report['renderer']:>8}"
        for mode, s in report["modes"].items():
            if "mean_mm" not in s:
                print(f"{head} {mode:>8}  no fix in any frame {s['refusals']}")
                continue
            print(f"{head} {mode:>8} {s['mean_mm']:7.3f} {s['std_mm']:7.3f} {s['min_mm']:7.3f} "
                  f"{s['max_mm']:7.3f} {s['p95_mm']:7.3f} {s['coverage_pct']:5.1f}%")
    for ratio in ratios:
        print(f"{ratio['distance_m']:>7.1f}m  Blender's mean error / ours ({ratio['mode']}): {ratio['ratio']:.2f}")
    return 0


def _run_negatives(args) -> int:
    from simulator.bench_negatives import run_negatives_command

    return run_negatives_command(args)


def _run_partial(args) -> int:
    from simulator.bench_partial import PartialConfig, format_partial, plot_partial, run_partial
    from simulator.reports import print_figures

    if args.frames < 1 or min(args.scales) <= 0:
        return report_bad_input(BadInput("--frames must be at least 1 and every --scales positive"), args.json)
    config = PartialConfig(distances_m=tuple(args.distances), scales=tuple(args.scales), frames=args.frames,
                           seed=args.seed)
    report = run_partial(config, args.workers)
    if args.figures is not None:
        args.figures.mkdir(parents=True, exist_ok=True)
        (args.figures / "partial.json").write_text(json.dumps(report, indent=2) + "\n")
        plot_partial(report, args.figures / "partial.png")
        report["figures"] = [str(args.figures / "partial.png")]
    print(json.dumps(report, indent=2) if args.json else format_partial(report))
    print_figures(report.get("figures", []), args.json)
    return 0


def _write_report(report: dict, figures_dir: Path | None) -> None:
    """report.json beside the figures (the data they were drawn from)."""
    if figures_dir is not None:
        (figures_dir / "report.json").write_text(json.dumps(report, indent=2) + "\n")


def _print_report(report: dict, as_json: bool) -> None:
    from simulator.reports import format_table, print_figures

    if as_json:
        print(json.dumps(report, indent=2))
        print_figures(report.get("figures", []), as_json)
        return
    print(format_table(report["summary"], report["title"]))
    paper = report.get("paper")
    if paper:
        print(f"  paper        mean {paper['mean_mm']} mm, max {paper['max_mm']} mm, coverage {paper['coverage_pct']} %")
    for failure in report.get("failures", [])[:20]:
        print(f"  failed {failure['label'] or failure['index']}: {failure['reason'] or 'outlier'} "
              f"{failure['error_2d_mm'] if failure['error_2d_mm'] is not None else ''} {failure['message'] or ''}")
    print(f"  wall time    {report['wall_s']:.0f} s on {plural(report['workers'], 'worker')} (render + locate)")
    print_figures(report.get("figures", []), as_json)


def _run_grid_bench(args) -> int:
    from simulator.bench_grid import RealBench, bench_grid, bench_real

    if args.bench_name == "grid":
        try:
            report = bench_grid(args.figures, args.scale, args.seed, args.workers, args.limit, args.scene,
                                args.yaw_jitter)
        except ValueError as error:
            return report_bad_input(BadInput(str(error)), args.json)
    else:
        profile = None
        if args.profile is not None:
            from pydantic import ValidationError

            from shared_schemas import DeviceProfile

            try:
                profile = DeviceProfile.model_validate_json(args.profile.read_text())
            except (OSError, ValidationError) as error:
                problem = BadInput(f"--profile {describe_file_error(args.profile, error)}", field="profile")
                return report_bad_input(problem, args.json)
        report = bench_real(args.figures, RealBench(calibrated=not args.uncalibrated), args.scale, args.seed,
                            args.workers, args.limit, profile)
    _write_report(report, args.figures)
    _print_report(report, args.json)
    return 0


def _run_calibration_bench(args) -> int:
    from simulator.bench_calibration import CORNER_VIEWS, bench_calibration, format_calibration

    corner_views = CORNER_VIEWS if args.corner_views is None else args.corner_views
    if args.views < 3 or args.scale <= 0 or not 0 <= corner_views <= args.views:
        problem = BadInput("--views must be at least 3, --scale positive and --corner-views within 0..views")
        return report_bad_input(problem, args.json)
    result = bench_calibration(args.views, args.scale, args.seed, args.lens, not args.no_poor_sets,
                               corner_views=corner_views)
    profile = result["report"]["profile"]
    if args.out is not None:
        if profile is None:
            print("error: the good set was refused: no profile to write", file=sys.stderr)
        else:
            args.out.write_text(json.dumps(profile, indent=2) + "\n")
            result["profile_written"] = str(args.out)
    print(json.dumps(result, indent=2) if args.json else format_calibration(result))
    return 0 if profile is not None else 1


def _run_boards_bench(args) -> int:
    from simulator.bench_boards import bench_boards, format_boards

    result = bench_boards(args.videos)
    print(json.dumps(result, indent=2) if args.json else format_boards(result))
    return 0


def _run_real_leds_bench(args) -> int:
    from simulator.bench_real_leds import bench_real_leds, format_real_leds

    result = bench_real_leds(args.cache)
    print(json.dumps(result, indent=2) if args.json else format_real_leds(result))
    return 0


def _run_sweep(args) -> int:
    from simulator.bench_sweeps import bench_distance, bench_tilt, format_sweep
    from simulator.reports import print_figures

    if args.bench_name == "distance":
        report = bench_distance(args.figures, args.distances, args.scale, args.seed, args.workers, args.yaw_jitter)
        text = format_sweep(report, "distance_m", "m")
    else:
        report = bench_tilt(args.figures, args.tilts, args.scale, args.seed, args.workers)
        text = format_sweep(report, "tilt_deg", "deg")
    _write_report(report, args.figures)
    print(json.dumps(report, indent=2) if args.json else text)
    print_figures(report.get("figures", []), args.json)
    return 0


def _run_fidelity(args) -> int:
    from simulator.bench_fidelity import bench_fidelity, format_fidelity
    from simulator.reports import print_figures

    try:
        report = bench_fidelity(args.figures, args.distances, blender=args.blender)
    except RuntimeError as error:
        return report_bad_input(BadInput(str(error), field="blender"), args.json)
    _write_report(report, args.figures)
    print(json.dumps(report, indent=2) if args.json else format_fidelity(report))
    print_figures(report.get("figures", []), args.json)
    return 0


def _run_render_speed(args) -> int:
    from simulator.bench_render import bench_render

    report = bench_render(args.scene, args.repeats)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"render {report['scene']} sample {report['sample']}, {report['frame']}, "
          f"{plural(report['repeats'], 'run')}, {plural(report['cpu_count'], 'core')}")
    print(f"median {report['median_ms']:.0f} ms wall (max {report['max_ms']:.0f} ms), {report['cpu_median_ms']:.0f} ms CPU; "
          f"load average {report['load_average_1min']:.1f}")
    print(f"for scale: one full-frame Gaussian draw takes {report['gaussian_noise_median_ms']:.0f} ms")
    return 0


def _run_speed(args) -> int:
    from simulator.bench_speed import SpeedConfig, format_speed, markdown_table, plot_speed, read_report, run_speed
    from simulator.reports import print_figures

    if args.frames < 1 or args.rounds < 1 or args.repeats < 1 or min(args.distance) <= 0:
        return report_bad_input(BadInput("--frames, --rounds and --repeats must be at least 1 and every --distance "
                                         "positive"), args.json)
    try:
        before = None if args.baseline is None else read_report(args.baseline)
        if args.report is not None:
            report = read_report(args.report)
        else:
            paths = SPEED_PATHS if "all" in args.path else tuple(dict.fromkeys(args.path))
            report = run_speed(SpeedConfig(paths=paths, frames=args.frames, rounds=args.rounds, repeats=args.repeats,
                                           distances_m=tuple(args.distance), gravity=not args.no_gravity,
                                           seed=args.seed))
    except (OSError, ValueError) as error:
        return report_bad_input(BadInput(str(error)), args.json)
    if args.figures is not None:
        args.figures.mkdir(parents=True, exist_ok=True)
        (args.figures / "speed.json").write_text(json.dumps(report, indent=2) + "\n")
        plot_speed(report, args.figures / "speed.png", before)
        report["figures"] = [str(args.figures / "speed.png")]
    if args.json:
        print(json.dumps(report, indent=2))
    elif args.markdown:
        print(markdown_table(report, before))
    else:
        print(format_speed(report))
    print_figures(report.get("figures", []), args.json)
    return 0


def _run_robustness(args) -> int:
    from simulator.bench_robustness import GROUPS, RobustnessConfig, format_robustness, run_robustness

    unknown = sorted(set(args.effects) - set(GROUPS))
    if unknown or args.frames < 1 or min(args.scales) <= 0:
        problem = BadInput(f"--frames must be at least 1, every --scales positive and --effects among "
                           f"{', '.join(GROUPS)}{' (unknown: ' + ', '.join(unknown) + ')' if unknown else ''}")
        return report_bad_input(problem, args.json)
    config = RobustnessConfig(distances_m=tuple(args.distances), scales=tuple(args.scales), frames=args.frames,
                              effects=tuple(args.effects), seed=args.seed)
    report = run_robustness(config, args.workers)
    print(json.dumps(report, indent=2) if args.json else format_robustness(report))
    return 0
