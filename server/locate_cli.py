"""`lumipose locate FRAME`: the camera's position and attitude from one recorded frame, on this machine.

Each step is its own function (inputs, options, printing) so the command's flags stay readable.
Exit codes: 0 a fix, 1 no fix (the reason is printed), 2 bad input (`shared_schemas.cli`).
"""

from __future__ import annotations

from pathlib import Path

from shared_schemas import DEMO_MAP_NAME
from shared_schemas.cli import (
    EXIT_NO_FIX,
    EXIT_OK,
    BadInput,
    describe_file_error,
    number,
    read_map_argument,
    report_bad_input,
)


def add_locate_command(commands) -> None:
    parser = commands.add_parser("locate", help="locate the camera from one recorded frame")
    parser.add_argument("frame", type=Path, help="NAME.json, NAME.y, NAME.yuv or NAME.png")
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
    parser.add_argument(
        "--profile",
        type=Path,
        action="append",
        default=[],
        help="a device profile file (for example a calibrated one) the frame's camera.profile may name; repeatable",
    )
    parser.add_argument("--json", action="store_true", help="print the contract's result (or error) as JSON")
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
        help="also write a picture of what the pipeline saw (panel, contour, sides, corners, centre, the result)",
    )
    parser.set_defaults(run=run_locate)


def run_locate(args) -> int:
    from dataclasses import replace

    from server.diagnostics import Diagnostics
    from server.locator import locate
    from server.options import LocateOptions

    try:
        profiles = read_profiles(args.profile)
        beacon_map = read_map(args.map, args.data_dir)
        frame = read_frame(args.frame, profiles)
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    diagnostics = Diagnostics() if args.annotate else None
    result = locate(frame, beacon_map, LocateOptions(pipeline=replace(pipeline_options(args), diagnostics=diagnostics)))
    if diagnostics is not None:
        try:
            write_annotation(args.annotate, frame, diagnostics, result)
        except BadInput as problem:
            return report_bad_input(problem, as_json=args.json)
    print_result(result, frame, as_json=args.json)
    return EXIT_OK if result.ok else EXIT_NO_FIX


def read_profiles(paths: list[Path]):
    """The bundled device profiles and those in `paths` (calibrated ones), by id."""
    from server.camera import profile_table
    from shared_schemas import DeviceProfile

    given = []
    for path in paths:
        try:
            given.append(DeviceProfile.model_validate_json(path.read_bytes()))
        except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError
            raise BadInput(
                f"cannot read the device profile {describe_file_error(path, error)}", field="profile"
            ) from None
    try:
        return profile_table(given)
    except ValueError as error:
        raise BadInput(str(error), field="profile") from None


def read_map(value: str, data_dir: Path | None = None):
    """The map `--map` means: a file if one is there, else a map of that name (stored in `data_dir`, or bundled)."""
    return read_map_argument(value, data_dir)


def read_frame(path: Path, profiles):
    from server.ingest import read_fixture
    from server.outcomes import FrameError

    try:
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


def write_annotation(path: Path, frame, diagnostics, result) -> None:
    """The picture of what the pipeline saw (`server.annotate`) as a PNG file at `path`."""
    from server.annotate import annotate

    try:
        path.write_bytes(annotate(frame, diagnostics, result))
    except OSError as error:
        raise BadInput(f"cannot write the picture {path}: {error.strerror or error}", field="annotate") from None


def print_result(result, frame, as_json: bool) -> None:
    """The contract's LocateResult as JSON, or a few lines for people (with the error against the
    frame's ground truth when it has one)."""
    if as_json:
        print(result.model_dump_json(by_alias=True, indent=2))
        return
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
        f"quality   reprojection {number(result.reprojection_error_px, 3)} px, "
        f"ambiguity ratio {number(result.ambiguity_ratio)}, {result.timing_ms['total']:.1f} ms"
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
