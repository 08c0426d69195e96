"""`lumipose vlc stripes FRAME`: the blink frequency, duty and edge width of the stripes in a picture
(`server.vlc.stripes`), e.g. of a camera looking through a diffuser at an LED keyed on and off.

The picture is read as it is stored (its luma, BT.601 for colour, as `server.photos` does; no EXIF
turn: the rows must be the sensor's readout rows). Exit codes: 0 measured, 1 no stripes, 2 bad input.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from shared_schemas.cli import EXIT_NO_FIX, EXIT_OK, BadInput, report_bad_input


def add_vlc_command(commands) -> None:
    vlc = commands.add_parser("vlc", help="rolling-shutter stripes in a picture (VLC)")
    steps = vlc.add_subparsers(dest="vlc_command", required=True)
    stripes = steps.add_parser(
        "stripes", help="the blink frequency, duty and edge width of a picture's stripes (docs/vlc.md, 'A real frame')"
    )
    stripes.add_argument(
        "frame",
        type=Path,
        metavar="FRAME",
        help="an 8-bit picture (PNG, JPEG, HEIC), read as stored: its EXIF orientation is not applied, since the "
        "stripes follow the sensor's readout rows, which are the stored rows",
    )
    timing = stripes.add_mutually_exclusive_group(required=True)
    timing.add_argument("--skew-s", type=float, help="readout time from the first row to the last (s)")
    timing.add_argument("--row-time-us", type=float, help="time from one row's exposure start to the next's (us)")
    stripes.add_argument("--exposure-s", type=float, required=True, help="exposure time (s)")
    stripes.add_argument(
        "--region",
        type=int,
        nargs=4,
        metavar=("X", "Y", "W", "H"),
        help="read only this box (default: the whole frame)",
    )
    stripes.add_argument(
        "--tone-curve",
        choices=["none", "srgb"],
        default="none",
        help="undo this curve before measuring (srgb: the inverse sRGB curve, as the server does for tone_curve srgb)",
    )
    stripes.add_argument("--json", action="store_true", help="print the measurement as JSON")
    stripes.set_defaults(run=_run_stripes)


def _luma(path: Path):
    """The picture's luma as stored, through `server.photos`' reader and its guards (8-bit only, its size
    checked from the header); never reduced, since a reduced decode would merge rows."""
    from server.photos import MAX_JPEG_PIXELS, PhotoError, read_photo

    try:
        data = path.read_bytes()
    except OSError as error:
        raise BadInput(f"cannot read {path}: {error}", field="frame") from None
    try:
        # as stored, not turned upright by its EXIF orientation: the stripes follow the sensor's readout rows
        return read_photo(data, path.name, max_pixels=MAX_JPEG_PIXELS, upright=False).pixels
    except PhotoError as error:
        raise BadInput(str(error), field="frame") from None


def _run_stripes(args) -> int:
    import cv2
    import numpy as np

    from server.tone import SRGB_TO_LINEAR_DN
    from server.vlc.decoder import panel_pixels, row_time_s
    from server.vlc.stripes import (
        NoStripes,
        TurnedRules,
        measure_stripes,
        row_signal,
        stripe_axis,
        turned_frame_problem,
    )

    try:
        pixels = _luma(args.frame)
        height, width = pixels.shape
        if not args.exposure_s > 0:
            raise BadInput(f"--exposure-s must be positive, got {args.exposure_s}", field="exposure_s")
        if args.row_time_us is not None:
            if not args.row_time_us > 0:
                raise BadInput(f"--row-time-us must be positive, got {args.row_time_us}", field="row_time_us")
            row_time = args.row_time_us * 1e-6
        else:
            try:
                row_time = row_time_s(args.skew_s, height)
            except ValueError as error:
                raise BadInput(str(error), field="skew_s") from None
        x, y, w, h = args.region or (0, 0, width, height)
        if w < 1 or h < 1 or x < 0 or y < 0 or x + w > width or y + h > height:
            raise BadInput(f"--region {x} {y} {w} {h} is not inside the {width}x{height} frame", field="region")
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    values = cv2.LUT(pixels, SRGB_TO_LINEAR_DN) if args.tone_curve == "srgb" else pixels
    mask = np.ones((h, w), bool)
    panel = panel_pixels(values, mask, (y, x), TurnedRules().edge_margin_px)
    axis = stripe_axis([panel])
    signal = row_signal(values, mask, (y, x), row_time, args.exposure_s)
    measured = NoStripes("too few rows") if signal is None else measure_stripes(*signal, row_time, args.exposure_s)
    turned = turned_frame_problem(values, [panel], [(x, y, w, h)])
    if args.json:
        body = {
            "frame": str(args.frame),
            "row_time_us": row_time * 1e6,
            "exposure_s": args.exposure_s,
            "region": [x, y, w, h],
            "tone_curve": args.tone_curve,
            "axis_ratio": axis.ratio,
        }
        if isinstance(measured, NoStripes):
            body["no_stripes"] = measured.reason
        else:
            body.update(asdict(measured), edge_width_rows=measured.edge_width_rows)
        print(json.dumps(body, indent=2))
        return EXIT_NO_FIX if isinstance(measured, NoStripes) else EXIT_OK
    if isinstance(measured, NoStripes):
        print(f"no stripes: {measured.reason}")
        if turned:
            print(turned)
        return EXIT_NO_FIX
    m = measured
    print(f"rows            {m.rows} read, {row_time * 1e6:.3f} us apart, exposure {args.exposure_s:.4g} s")
    print(
        f"edges           {m.rising_edges} rising, {m.falling_edges} falling; "
        f"levels {m.dark_dn:.1f} / {m.bright_dn:.1f} DN"
    )
    print(f"period          {m.period_rows:.3f} +- {m.period_rows_sigma:.3f} rows")
    print(f"frequency       {m.frequency_hz:.2f} +- {m.frequency_hz_sigma:.2f} Hz")
    print(f"duty            {100 * m.duty:.2f} +- {100 * m.duty_sigma:.2f} % (at the half level)")
    print(
        f"edge 10-90 %    rising {m.rise_width_rows:.2f} +- {m.rise_width_rows_sigma:.2f}, "
        f"falling {m.fall_width_rows:.2f} +- {m.fall_width_rows_sigma:.2f} rows; "
        f"the exposure's box predicts {m.predicted_width_rows:.2f}"
    )
    return EXIT_OK
