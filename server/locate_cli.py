"""`lumipose locate FRAME...`: the camera's position and attitude from recorded frames, on this machine.

Several frames (a walk, listed as shot) go through `server.locator.locate` in turn, with `--device`
through one session as the service's do for a device: a burst's ID frames before its pose frame, as
the app sends them (`shared_schemas.captures`). One line (or JSON line) per frame, in the order given.

Each step is its own function (inputs, options, printing) so the command's flags stay readable.
Exit codes: 0 a fix (several frames: `captures.all_located`), 1 no fix (the reason is printed), 2 bad input.
Several frames: a frame that cannot be read (a damaged photo, a missing file) is its own line, its error as
the API's error body (`ErrorBody`), and the others are located (its kind unknown, it ends the capture before
it: no frame moves into another capture); the exit code is the worst of them (2 over 1 over 0). A bad option
(map, profile, --camera) is still one error for the whole call.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from shared_schemas import DEMO_MAP_NAME
from shared_schemas.captures import add_frame_series_arguments, annotation_paths
from shared_schemas.cli import (
    EXIT_BAD_INPUT,
    EXIT_NO_FIX,
    EXIT_OK,
    BadInput,
    add_profile_argument,
    check_beacon_id,
    number,
    read_map_argument,
    reads_environment,
    report_bad_input,
)


def add_locate_command(commands) -> None:
    # --data-dir reads LUMIPOSE_DATA_DIR: the stored maps of the service on this machine
    parser = commands.add_parser("locate", help="locate the camera from recorded frames")
    reads_environment(parser, frozenset({"--data-dir"}))
    add_frame_series_arguments(parser)
    parser.add_argument(
        "--map",
        default=DEMO_MAP_NAME,
        help="beacon map: a file, or a map's name (bundled, or stored in --data-dir) (default: %(default)s, bundled)",
    )
    parser.add_argument(
        "--data-dir",
        type=Path,
        help="a service's data folder, whose stored maps --map may name (default: $LUMIPOSE_DATA_DIR, else none)",
    )
    add_profile_argument(parser, "a photo uses the last one given, else the one its EXIF make and model name")
    parser.add_argument(
        "--camera",
        metavar="FX,FY,CX,CY[,K1,K2,P1,P2,K3]",
        help="a photo's intrinsics in pixels of the upright photo (its EXIF orientation applied); wins over "
        "--profile and EXIF (default: none)",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the contract's result (or error) as JSON; several frames: one result per line (JSON lines)",
    )
    parser.add_argument(
        "--truth",
        type=Path,
        metavar="JSON",
        help="the camera's true pose (position_m, rotation_wc in the map frame, as samples/*.truth.json): print "
        "the fix's error against it, as for a rendered frame (one frame only; default: the frame's own, if any)",
    )
    parser.add_argument("--square-corners", action="store_true", help="the paper's square-corner path")
    parser.add_argument("--no-subpixel", action="store_true", help="corners from the polygon stage only")
    parser.add_argument(
        "--gravity",
        choices=["auto", "always", "never"],
        default="auto",
        help="use the frame's gravity vector (default: auto, where it helps)",
    )
    parser.add_argument(
        "--annotate",
        type=Path,
        metavar="PNG",
        help="also write a picture of what the pipeline saw (panel, contour, sides, corners, centre, the result); "
        "several frames: one PNG each, named PNG-<frame>.png",
    )
    parser.set_defaults(run=run_locate)


def run_locate(args) -> int:
    from dataclasses import replace

    from server.diagnostics import Diagnostics
    from server.locator import in_device_session, locate
    from server.options import LocateOptions
    from server.tracking.devices import Devices
    from shared_schemas import FrameKind, LocateResult
    from shared_schemas.captures import all_located, bursts_in_upload_order

    try:
        profiles, profile = read_profiles(args.profile)
        beacon_map = read_map(args.map, args.data_dir)
        check_beacon_id(args.beacon_id, beacon_map)
        pictures = annotation_paths(args.annotate, args.frames)
        camera = None if args.camera is None else read_camera(args.camera)  # its fault is the call's, not a frame's
        truth = None if args.truth is None else read_truth(args.truth, len(args.frames))
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    frames, unreadable = read_frames(args.frames, profiles, profile, camera)
    if truth is not None and frames:
        frames[0] = replace(frames[0], meta=frames[0].meta.model_copy(update={"ground_truth": truth}))
    if len(args.frames) == 1 and unreadable:  # one frame: its fault is the call's
        return report_bad_input(unreadable[0], as_json=args.json)
    options = LocateOptions(pipeline=pipeline_options(args))
    devices = Devices() if args.device is not None else None
    results: dict[int, LocateResult] = {}
    # an unreadable frame's kind is unknown: it ends the capture before it, so it moves no frame into another
    kinds = [frames[index].meta.frame_kind if index in frames else FrameKind.pose for index in range(len(args.frames))]
    for capture in bursts_in_upload_order(kinds):
        for index in (index for index in capture if index in frames):
            picture = pictures[index]
            diagnostics = Diagnostics() if picture is not None else None
            results[index] = locate(
                frames[index],
                beacon_map,
                replace(options, pipeline=replace(options.pipeline, diagnostics=diagnostics)),
                beacon_id=args.beacon_id,
                device_id=args.device,
                devices=devices,
            )
            if picture is not None and diagnostics is not None:
                try:
                    in_session = in_device_session(beacon_map, args.beacon_id, args.device)
                    write_annotation(picture, frames[index], diagnostics, results[index], in_session)
                except BadInput as problem:
                    return report_bad_input(problem, as_json=args.json)
    if len(args.frames) == 1:
        print_result(results[0], frames[0], as_json=args.json, beacon_map=beacon_map)
    else:
        for index, path in enumerate(args.frames):
            if index in unreadable:
                print_error_line(path, unreadable[index], as_json=args.json)
            else:
                print_line(path, results[index], frames[index], as_json=args.json)
    if unreadable:
        return EXIT_BAD_INPUT
    return EXIT_OK if all_located(list(results.values())) else EXIT_NO_FIX


def read_frames(paths: list[Path], profiles, profile=None, camera=None):
    """Each frame read on its own: (the readable ones, the others' BadInput), by index."""
    frames, unreadable = {}, {}
    for index, path in enumerate(paths):
        try:
            frames[index] = read_frame(path, profiles, profile, camera)
        except BadInput as problem:
            unreadable[index] = problem
    return frames, unreadable


def read_camera(camera_text: str):
    """`--camera`'s intrinsics, or BadInput naming the fault."""
    from server.camera import parse_camera_arg

    try:
        return parse_camera_arg(camera_text)
    except ValueError as error:
        raise BadInput(str(error), field="camera") from None


def read_truth(path: Path, frame_count: int):
    """`--truth`'s pose (a GroundTruth: position_m, rotation_wc; other keys ignored), or BadInput naming the fault."""
    from pydantic import ValidationError

    from shared_schemas.models import GroundTruth

    if frame_count != 1:
        raise BadInput("--truth is one frame's pose: give one frame with it", field="truth")
    try:
        return GroundTruth.model_validate_json(path.read_bytes())
    except OSError as error:
        raise BadInput(f"cannot read the truth {path}: {error.strerror or error}", field="truth") from None
    except ValidationError as error:
        problem = error.errors()[0]
        where = ".".join(map(str, problem["loc"])) or "the file"
        raise BadInput(
            f"{path} is not a pose (position_m, rotation_wc): {where}: {problem['msg']}", field="truth"
        ) from None


def read_profiles(values: list[str]):
    """The device profiles a frame may name (bundled and `--profile` files) and the last one given, if any."""
    from server.camera import resolve_profile_args

    try:
        return resolve_profile_args(values)
    except ValueError as error:
        raise BadInput(str(error), field="profile") from None


def read_map(value: str, data_dir: Path | None = None):
    """The map `--map` means: a file if one is there, else a map of that name (stored in `data_dir`, or bundled)."""
    return read_map_argument(value, data_dir)


def read_frame(path: Path, profiles, profile=None, camera=None):
    """A recorded frame (its JSON names its camera) or a photo (`camera`, `--camera`'s intrinsics > `profile` >
    EXIF)."""
    from server.ingest import is_photo, read_fixture, read_photo_file
    from server.outcomes import FrameError

    try:
        if is_photo(path):
            return read_photo_file(path, profiles, camera, profile)[0]
        if camera is not None:
            raise BadInput("--camera is for photos; a recorded frame's JSON names its camera", field="camera")
        return read_fixture(path, profiles)
    except FrameError as error:
        raise BadInput(error.message, field=error.field, error="bad_frame") from None


def pipeline_options(args):
    from server.pipeline import CornerMethod, PipelineOptions
    from server.pose.solve import GravityMode

    return PipelineOptions(
        corner_method=CornerMethod.square if args.square_corners else CornerMethod.rounded,
        subpixel=not args.no_subpixel,
        gravity_mode=GravityMode(args.gravity),
    )


def write_annotation(path: Path, frame, diagnostics, result, in_session: bool = False) -> None:
    """The picture of what the pipeline saw (`server.annotate`) as a PNG file at `path`."""
    from server.annotate import annotate

    try:
        path.write_bytes(annotate(frame, diagnostics, result, in_session))
    except OSError as error:
        raise BadInput(f"cannot write the picture {path}: {error.strerror or error}", field="annotate") from None
    print(f"picture: {path}", file=sys.stderr)  # stdout stays the result alone (--json)


def print_result(result, frame, as_json: bool, beacon_map=None) -> None:
    """The contract's LocateResult as JSON, or a few lines for people (with the error against the
    frame's ground truth when it has one, and the intrinsics used and how sure they are)."""
    if as_json:
        print(result.model_dump_json(by_alias=True, indent=2))
        return
    if frame.camera_used is not None:
        print_camera_used(frame.camera_used, result, beacon_map)
    if not result.ok:
        print(f"no fix: {result.reason}: {result.message}")
        return
    assert result.position_m is not None and result.yaw_pitch_roll_deg is not None  # outcomes.located sets both
    x, y, z = result.position_m
    yaw, pitch, roll = result.yaw_pitch_roll_deg
    print(f"position  x={x:+.4f} m  y={y:+.4f} m  z={z:+.4f} m   (beacon {result.beacon_id})")
    print(
        f"attitude  yaw={yaw:+.2f}  pitch={pitch:+.2f}  roll={roll:+.2f} deg"
        f"   gravity prior {'used' if result.gravity_used else 'not used'}"
    )
    # an outline fit (a cut panel, a rectangle, a circle) has no square's two poses to compare
    ambiguity = "n/a" if result.ambiguity_ratio is None else number(result.ambiguity_ratio)
    reprojection = "n/a" if result.reprojection_error_px is None else f"{number(result.reprojection_error_px, 3)} px"
    print(f"quality   reprojection {reprojection}, ambiguity ratio {ambiguity}, {result.timing_ms['total']:.1f} ms")
    errors = truth_errors_mm(result.position_m, frame)
    if errors is not None:
        print(f"truth     error 2D {errors[0]:.2f} mm, 3D {errors[1]:.2f} mm")
    for warning in result.warnings:
        print(f"warning   {warning}")


def print_camera_used(camera_used, result, beacon_map) -> None:
    """Which intrinsics a photo was located with, and what their focal uncertainty means at the fix's distance
    (a relative focal error scales the distance along the ray by as much)."""
    k = camera_used
    print(f"camera    fx={k.fx:.1f} fy={k.fy:.1f} cx={k.cx:.1f} cy={k.cy:.1f} px from {k.detail}")
    sigma = camera_used.focal_sigma_rel
    if sigma is None:
        print("          focal uncertainty unknown (intrinsics as given, not checked here)")
        return
    line = f"          focal uncertainty {100 * sigma:.2g} %"
    beacon = beacon_map.beacon(result.beacon_id) if beacon_map and result.beacon_id is not None else None
    if result.position_m is not None and beacon is not None:
        distance_m = math.dist(result.position_m, beacon.center_m)
        line += f", about {1000 * sigma * distance_m:.1f} mm along the ray at this fix's {distance_m:.2f} m"
    print(line)


def print_line(path: Path, result, frame, as_json: bool) -> None:
    """One frame of several: its result as one JSON line, or its name and fix (or reason) on one line."""
    if as_json:
        print(result.model_dump_json(by_alias=True))
        return
    if not result.ok:
        print(f"{path.name}  no fix: {result.reason}: {result.message}")
        return
    assert result.position_m is not None  # outcomes.located sets it
    x, y, z = result.position_m
    errors = truth_errors_mm(result.position_m, frame)
    error = "" if errors is None else f"  truth error 2D {errors[0]:.1f} mm"
    print(f"{path.name}  x={x:+.4f} y={y:+.4f} z={z:+.4f} m  beacon {result.beacon_id}{error}")


def print_error_line(path: Path, problem: BadInput, as_json: bool) -> None:
    """One frame of several that cannot be read: its error body as one JSON line, or its name and the error."""
    if as_json:
        print(problem.body.model_dump_json())
        return
    print(f"{path.name}  error: {problem.body.message}")


def truth_errors_mm(position_m, frame) -> tuple[float, float] | None:
    """The fix's 2-D and 3-D distance from the frame's ground truth, in mm; None for a frame without one."""
    truth = frame.meta.ground_truth
    if truth is None:
        return None
    return 1000 * math.dist(position_m[:2], truth.position_m[:2]), 1000 * math.dist(position_m, truth.position_m)
