"""`lumipose locate FRAME`: the camera's position and attitude from one recorded frame, on this machine.

Each step is its own function (inputs, options, printing) so the command's flags stay readable.
Exit codes: 0 a fix, 1 no fix (the reason is printed), 2 bad input (`shared_schemas.cli`).
"""

from __future__ import annotations

from pathlib import Path

from shared_schemas import DEMO_MAP_PATH
from shared_schemas.cli import EXIT_NO_FIX, EXIT_OK, BadInput, report_bad_input


def add_locate_command(commands) -> None:
    parser = commands.add_parser("locate", help="locate the camera from one recorded frame")
    parser.add_argument(
        "frame", type=Path, help="a recorded frame (NAME.json beside NAME.y/.yuv/.png) or a photo (JPEG, PNG, HEIC)"
    )
    parser.add_argument("--map", type=Path, default=DEMO_MAP_PATH, help="beacon map (default: bundled demo)")
    parser.add_argument(
        "--profile",
        action="append",
        default=[],
        metavar="NAME|FILE",
        help="a device profile id or file (a file is registered, so a frame's camera.profile may name it); "
        "a photo uses the last one given; repeatable (default: none; a photo's EXIF make and model pick one)",
    )
    parser.add_argument(
        "--camera",
        metavar="FX,FY,CX,CY[,K1,K2,P1,P2,K3]",
        help="a photo's intrinsics in pixels of the stored image; wins over --profile and EXIF (default: none)",
    )
    parser.add_argument("--json", action="store_true", help="print the contract's result (or error) as JSON")
    parser.add_argument("--square-corners", action="store_true", help="the paper's square-corner path")
    parser.add_argument("--no-subpixel", action="store_true", help="corners from the polygon stage only")
    parser.add_argument(
        "--gravity",
        choices=["auto", "always", "never"],
        default="auto",
        help="use the frame's gravity vector (default: where it helps)",
    )
    parser.set_defaults(run=run_locate)


def run_locate(args) -> int:
    from server.locator import locate
    from server.options import LocateOptions

    try:
        profiles, profile = read_profiles(args.profile)
        beacon_map = read_map(args.map)
        frame = read_frame(args.frame, profiles, profile, args.camera)
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    result = locate(frame, beacon_map, LocateOptions(pipeline=pipeline_options(args)))
    print_result(result, frame, as_json=args.json, beacon_map=beacon_map)
    return EXIT_OK if result.ok else EXIT_NO_FIX


def read_profiles(values: list[str]):
    """The device profiles a frame may name (bundled and `--profile` files) and the last one given, if any."""
    from server.camera import resolve_profile_args

    try:
        return resolve_profile_args(values)
    except ValueError as error:
        raise BadInput(str(error), field="profile") from None


def read_map(path: Path):
    from shared_schemas import load_map

    try:
        return load_map(path)
    except (OSError, ValueError) as error:
        raise BadInput(f"cannot read map {path}: {error}", field="map") from None


def read_frame(path: Path, profiles, profile=None, camera_text: str | None = None):
    """A recorded frame (its JSON names its camera) or a photo (`--camera` > `profile` > EXIF)."""
    from server.camera import parse_camera_arg
    from server.ingest import is_photo, read_fixture, read_photo_file
    from server.outcomes import FrameError

    try:
        camera = None if camera_text is None else parse_camera_arg(camera_text)
    except ValueError as error:
        raise BadInput(str(error), field="camera") from None
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
    print(
        f"quality   reprojection {result.reprojection_error_px:.3f} px, "
        f"ambiguity ratio {result.ambiguity_ratio:.2f}, {result.timing_ms['total']:.1f} ms"
    )
    truth = frame.meta.ground_truth
    if truth is not None:
        dx, dy, dz = (a - b for a, b in zip((x, y, z), truth.position_m, strict=True))
        print(
            f"truth     error 2D {1000 * (dx * dx + dy * dy) ** 0.5:.2f} mm, 3D "
            f"{1000 * (dx * dx + dy * dy + dz * dz) ** 0.5:.2f} mm"
        )
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
    beacon = next((b for b in beacon_map.beacons if b.id == result.beacon_id), None) if beacon_map else None
    if result.position_m is not None and beacon is not None:
        distance_m = sum((a - b) ** 2 for a, b in zip(result.position_m, beacon.center_m, strict=True)) ** 0.5
        line += f", about {1000 * sigma * distance_m:.1f} mm along the ray at this fix's {distance_m:.2f} m"
    print(line)
