"""`lumipose calibrate board` and `lumipose calibrate camera` (issue 14).

Exit codes: 0 calibrated (or the board written), 1 the set refused (the advice is printed), 2 bad input.
"""

from __future__ import annotations

from pathlib import Path

from shared_schemas.cli import BadInput, describe_file_error, describe_validation_error, report_bad_input

EXIT_OK, EXIT_REFUSED = 0, 1
DICTIONARIES = (
    *(f"DICT_{bits}X{bits}_{n}" for bits in (4, 5, 6, 7) for n in (50, 100, 250, 1000)),
    "DICT_ARUCO_ORIGINAL",
    "DICT_APRILTAG_16h5",
    "DICT_APRILTAG_25h9",
    "DICT_APRILTAG_36h10",
    "DICT_APRILTAG_36h11",
    "DICT_ARUCO_MIP_36h12",
)  # shared_schemas.calibration.ArucoDictionary, without importing it for every `lumipose --help`


def add_commands(commands) -> None:
    """Add `calibrate board` and `calibrate camera` to an argparse subparsers object."""
    calibrate = commands.add_parser("calibrate", help="camera calibration with a ChArUco board or a chessboard")
    steps = calibrate.add_subparsers(dest="step", required=True)
    board = steps.add_parser(
        "board", help="write a printable board and its spec (board.json): also the spec of a board you already own"
    )
    board.add_argument("--out", type=Path, required=True, help="board.pdf (to print) or board.png (for a screen)")
    board.add_argument(
        "--kind", default="charuco", choices=("charuco", "chessboard"), help="a ChArUco board or a plain chessboard"
    )
    board.add_argument(
        "--squares",
        default="11x8",
        help="squares across x down (default: 11x8, on A4 or Letter landscape); OpenCV's '9x6' chessboard pattern "
        "(inner corners) has 10x7 squares",
    )
    board.add_argument("--square-mm", type=float, default=24.0, help="side of a square")
    board.add_argument("--marker-mm", type=float, default=None, help="side of a marker (default: 0.6 of a square)")
    board.add_argument(
        "--dictionary", default="DICT_5X5_100", choices=DICTIONARIES, help="ArUco dictionary of the markers"
    )
    board.add_argument(
        "--legacy", action="store_true", help="OpenCV's ChArUco layout before 4.6 (differs for an even number of rows)"
    )
    board.add_argument("--first-marker", type=int, default=0, help="id of the top-left marker")
    board.add_argument("--inverted", action="store_true", help="printed inverted: white markers on black")
    board.add_argument("--paper", default="a4", choices=("a4", "letter"), help="a PDF's page, turned as the board fits")
    board.add_argument("--dpi", type=float, default=600.0, help="resolution of a PNG board's pixels")
    board.set_defaults(run=_run_board)
    camera = steps.add_parser("camera", help="calibrate a camera from photos of the board")
    camera.add_argument(
        "photos", type=Path, nargs="+", help="PNG, JPEG or HEIC photos of the board, grey or colour (turned upright)"
    )
    camera.add_argument(
        "--board",
        required=True,
        help="the board's spec: board.json (as `calibrate board` writes it) or that JSON itself",
    )
    camera.add_argument("--device", required=True, help="the phone's profile: a bundled id or a profile JSON file")
    camera.add_argument("--id", dest="profile_id", default=None, help="id of the calibrated profile")
    camera.add_argument("--out", type=Path, default=None, help="write the calibrated profile here (profile.json)")
    camera.add_argument("--json", action="store_true", help="print the CalibrationReport as JSON")
    camera.set_defaults(run=_run_camera)


def _fail(message: str, as_json: bool = False, field: str | None = None) -> int:
    """Bad input: `error: ...` on stderr, or the contract's ErrorBody on stdout with --json; exit 2."""
    return report_bad_input(BadInput(message, field=field), as_json=as_json)


def _run_board(args) -> int:
    from pydantic import ValidationError

    from server.calibration.board import describe_board, format_mm
    from server.calibration.printing import paper_name, write_board
    from shared_schemas.calibration import BoardSpec

    try:
        squares_x, squares_y = (int(n) for n in args.squares.lower().split("x"))
    except ValueError:
        return _fail(f"--squares must be like 11x8, got '{args.squares}'")
    charuco = args.kind == "charuco"
    marker_mm = args.marker_mm if args.marker_mm is not None or not charuco else 0.6 * args.square_mm
    # a chessboard's spec carries no ChArUco fields, so a ChArUco option given with it is refused by the spec
    given = {"dictionary": args.dictionary} if charuco or args.dictionary != "DICT_5X5_100" else {}
    try:
        spec = BoardSpec(
            kind=args.kind,
            squares_x=squares_x,
            squares_y=squares_y,
            square_m=args.square_mm / 1000,
            marker_m=marker_mm / 1000 if marker_mm is not None else None,
            legacy=args.legacy,
            first_marker_id=args.first_marker,
            inverted=args.inverted,
            **given,
        )
        printed, page = write_board(spec, args.out, args.dpi, args.paper)
    except ValidationError as error:
        return _fail(describe_validation_error(error, "board"))
    except (ValueError, OSError) as error:
        return _fail(str(error))
    on = (
        f" on a {page.width_mm:g} x {page.height_mm:g} mm page ({paper_name(page.paper)} "
        + ("landscape)" if page.landscape else "portrait)")
        if page is not None
        else ""
    )
    print(f"wrote {args.out} and {args.out.with_suffix('.json')}: {describe_board(printed)}{on}")
    check = "the check bar (100 mm) and a square" if page is not None else "a square"
    print(
        f"print at 100 % (no 'fit to page'), glue it flat, and measure {check}: if a square is not "
        f"{format_mm(printed.square_m)}, write the measured sizes into "
        f"{args.out.with_suffix('.json')}"
    )
    return EXIT_OK


def _spec(text: str):
    """The board spec of --board: a spec file, or the spec's JSON itself; raises ValueError saying what is wrong."""
    from pydantic import ValidationError

    from shared_schemas.calibration import BoardSpec

    if text.lstrip().startswith("{"):
        try:
            return BoardSpec.model_validate_json(text)
        except ValidationError as error:
            raise ValueError(f"--board is not a board spec: {describe_validation_error(error, 'board')}") from None
    path = Path(text)
    try:
        return BoardSpec.model_validate_json(path.read_text())
    except (OSError, UnicodeDecodeError) as error:
        raise ValueError(f"cannot read --board {path}: {error}") from None
    except ValidationError as error:
        raise ValueError(f"--board is not a board spec: {describe_file_error(path, error)}") from None


def _device(text: str):
    from pydantic import ValidationError

    from shared_schemas import DeviceProfile, device_profiles

    if text in device_profiles():
        return device_profiles()[text]
    path = Path(text)
    if not path.is_file():
        raise ValueError(
            f"--device '{text}' is neither a bundled profile ({', '.join(sorted(device_profiles()))}) "
            "nor a profile file"
        )
    try:
        return DeviceProfile.model_validate_json(path.read_text())
    except (ValidationError, OSError, UnicodeDecodeError) as error:
        raise ValueError(f"--device is not a device profile: {describe_file_error(path, error)}") from None


def _run_camera(args) -> int:

    from server.calibration.photos import PhotoError, find_views
    from server.calibration.report import CalibrationInputError, calibrate, no_board_report

    try:
        spec = _spec(args.board)
    except ValueError as error:
        return _fail(str(error), args.json, "board")
    try:
        device = _device(args.device)
    except ValueError as error:
        return _fail(str(error), args.json, "device")
    try:
        photos = [(str(path), path.read_bytes()) for path in args.photos]
        views, skipped = find_views(photos, spec)
    except OSError as error:
        return _fail(f"cannot read a photo: {error}", args.json, "photos")
    except PhotoError as error:
        return _fail(str(error), args.json, "photos")
    if not views:
        report = no_board_report(skipped)
        print(report.model_dump_json(by_alias=True, indent=2) if args.json else format_report(report))
        return EXIT_REFUSED
    try:
        report = calibrate(views, spec, device, args.profile_id)
    except CalibrationInputError as error:
        return _fail(str(error), args.json)
    report = report.model_copy(update={"views": report.views + skipped})
    if args.out is not None and report.profile is not None:
        args.out.write_text(report.profile.model_dump_json(indent=2, exclude_none=True) + "\n")
    if args.json:
        print(report.model_dump_json(by_alias=True, indent=2))
    else:
        print(format_report(report, args.out))
    return EXIT_OK if report.ok else EXIT_REFUSED


def format_report(report, out: Path | None = None) -> str:
    """The report as text: the fit, each parameter's sigma, coverage as a grid, each view."""
    lines = []
    profile, fitted = report.profile, report.fitted
    if profile is not None and profile.intrinsics is not None:
        lines.append(
            f"profile  {profile.id} at {profile.width}x{profile.height}"
            + (f", written to {out}" if out is not None else "")
        )
        p = profile.intrinsics
        camera = (p.fx, p.fy, p.cx, p.cy, profile.distortion)
    elif fitted is not None:  # a refused set's fit: shown, marked, never written
        lines.append(f"fitted   at {fitted.width}x{fitted.height}, NOT TRUSTED: the set was refused (below)")
        camera = (fitted.fx, fitted.fy, fitted.cx, fitted.cy, fitted.distortion)
    if profile is not None and profile.intrinsics is not None or fitted is not None:
        fx, fy, cx, cy, distortion = camera
        lines.append(f"pinhole  fx {fx:.2f}  fy {fy:.2f}  cx {cx:.2f}  cy {cy:.2f} px")
        names = ("k1", "k2", "p1", "p2", "k3")
        lines.append("distort  " + "  ".join(f"{n} {v:+.5f}" for n, v in zip(names, distortion, strict=False)))
    if report.rms_px is not None:
        lines.append(
            f"fit      RMS {report.rms_px:.3f} px, distortion 1-sigma up to {report.distortion_sigma_px:.3f} px"
            f" over the frame, most tilted view {report.max_tilt_deg:.1f} deg"
        )
    if report.sigmas:
        lines.append("sigma    " + "  ".join(f"{name} {value:.3g}" for name, value in report.sigmas.items()))
    lines.append(f"coverage {100 * report.coverage:.0f} % of the image's cells (corners per cell):")
    lines += ["  " + " ".join(f"{count:5d}" for count in row) for row in report.coverage_cells]
    lines.append(f"{'view':>24} {'corners':>7} {'RMS px':>7} {'tilt':>6} {'dist m':>6}")
    for view in report.views:
        numbers = (
            f"{view.rms_px:7.3f} {view.tilt_deg:6.1f} {view.distance_m:6.3f}"
            if view.rms_px is not None
            else f"{'-':>7} {'-':>6} {'-':>6}"
        )
        seen = [word for word, said in (("inverted", view.inverted), ("un-mirrored", view.mirrored)) if said]
        notes = ([view.note] if view.note else []) + seen
        lines.append(f"{view.name[-24:]:>24} {view.corners:7d} {numbers}" + (f"  {'; '.join(notes)}" if notes else ""))
    lines.append(("ok: " if report.ok else "refused: ") + (report.message or ""))
    lines += [f"  advice: {advice}" for advice in report.advice]
    return "\n".join(lines)
