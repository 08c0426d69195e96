"""`lumipose locate FRAME...`: the camera's position and attitude from recorded frames, on this machine.

Several frames (a walk, listed as shot) go through `server.locator.locate` in turn, with `--device`
through one session as the service's do for a device: a burst's ID frames before its pose frame, as
the app sends them (`shared_schemas.captures`). One line (or JSON line) per frame, in the order used (a
capture's ID frames, then its pose frame), printed as `lumipose client locate` prints them.

Each step is its own function (inputs, options, printing) so the command's flags stay readable.
Exit codes: 0 a fix (several frames: `captures.all_located`), 1 no fix (the reason is printed), 2 bad input.
Several frames: a frame that cannot be read (a damaged photo, a missing file) is its own line, its error as
the API's error body (`ErrorBody`), and the others are located (its kind unknown, it ends the capture before
it: no frame moves into another capture); the exit code is the worst of them (2 over 1 over 0). A bad option
(map, profile, --camera) is still one error for the whole call.
"""

from __future__ import annotations

from pathlib import Path

from shared_schemas import DEMO_MAP_NAME
from shared_schemas.captures import add_frame_series_arguments, annotation_paths, print_outcome, write_picture
from shared_schemas.cli import (
    EXIT_BAD_INPUT,
    EXIT_NO_FIX,
    EXIT_OK,
    BadInput,
    add_profile_argument,
    check_beacon_id,
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
        help="also write a PNG of what the pipeline saw (panel, contour, sides, corners, centre, the result); "
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
    several = len(args.frames) > 1
    results: list[LocateResult] = []
    # an unreadable frame's kind is unknown: it ends the capture before it, so it moves no frame into another
    kinds = [frames[index].meta.frame_kind if index in frames else FrameKind.pose for index in range(len(args.frames))]
    for capture in bursts_in_upload_order(kinds):
        for index in capture:  # printed as used: a capture's ID frames, then the pose frame they name
            name = args.frames[index].name
            if index in unreadable:
                print_outcome(name, unreadable[index].body, None, as_json=args.json, several=several)
                continue
            picture = pictures[index]
            diagnostics = Diagnostics() if picture is not None else None
            result = locate(
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
                    write_annotation(picture, frames[index], diagnostics, result, in_session)
                except BadInput as problem:
                    return report_bad_input(problem, as_json=args.json)
            truth = frames[index].meta.ground_truth
            print_outcome(name, result, truth, as_json=args.json, several=several, beacon_map=beacon_map)
            results.append(result)
    if unreadable:
        return EXIT_BAD_INPUT
    return EXIT_OK if all_located(results) else EXIT_NO_FIX


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

    write_picture(path, annotate(frame, diagnostics, result, in_session))
