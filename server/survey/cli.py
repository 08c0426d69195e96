"""`lumipose survey FRAMES... --map SKETCH --anchor ID --out MAP`: a room's map from recorded frames.

Exit codes: 0 the map was written, 1 the frames cannot give it (a panel not connected to the
anchor, no frame with two named panels; the reason is printed), 2 bad input (an unreadable frame,
sketch or labels file, an unknown anchor, a label naming a beacon the sketch lacks).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from shared_schemas.cli import BadInput, describe_file_error, read_map_argument, report_bad_input

EXIT_OK, EXIT_REFUSED = 0, 1


def add_survey_command(commands) -> None:
    parser = commands.add_parser(
        "survey", help="survey a room's panels from frames taken from the floor (bundle adjustment)"
    )
    parser.add_argument("frames", type=Path, nargs="+", help="recorded frames: NAME.json (beside NAME.y/.yuv/.png)")
    parser.add_argument(
        "--map",
        required=True,
        help="the sketch: the room's panels (IDs, shapes, sizes), a map file or a bundled map's name",
    )
    parser.add_argument("--anchor", type=int, required=True, help="the panel whose sketch centre and yaw fix the map")
    parser.add_argument("--out", type=Path, required=True, help="where to write the surveyed map")
    parser.add_argument("--labels", type=Path, help="JSON: a frame's file name -> list of PanelLabel")
    parser.add_argument("--name", help="the surveyed map's name (default: the --out file's stem)")
    parser.add_argument("--json", action="store_true", help="print the contract's SurveyReport as JSON")
    parser.set_defaults(run=run_survey_command)


def _read_labels(path: Path | None, frames: list[Path]):
    """Each frame's labels, by its path, file name or stem. A file whose keys name none of the frames is
    an error (a wrong file); keys of other frames are ignored, so one file serves every subset of a set
    (a frame left without labels is skipped, and the report says why)."""
    from pydantic import TypeAdapter

    from shared_schemas.survey import PanelLabel

    if path is None:
        return [[] for _ in frames]
    given = TypeAdapter(dict[str, list[PanelLabel]]).validate_json(path.read_bytes())
    names = [{str(f), f.name, f.stem} for f in frames]
    if given and not any(key in n for key in given for n in names):
        example = frames[0].name
        raise ValueError(f"its keys name none of the frames given (keys are frame file names, e.g. '{example}')")
    return [next((given[key] for key in given if key in n), []) for n in names]


def _print_report(report, out: Path) -> None:
    print(
        f"{'beacon':>6}  {'x (m)':>9} {'y (m)':>9} {'z (m)':>9}  {'sigma x/y/z (mm)':>18}  {'yaw (deg)':>9} "
        f"{'sigma':>6}  frames"
    )
    for b in report.beacons:
        x, y, z = b.center_m
        sx, sy, sz = (1000 * v for v in b.center_sigma_m)
        print(
            f"{b.beacon_id:>6}  {x:+9.4f} {y:+9.4f} {z:+9.4f}  {sx:5.2f} {sy:5.2f} {sz:5.2f}     "
            f"{b.yaw_deg:+9.3f} {b.yaw_sigma_deg:6.3f}  {b.frames}"
        )
    used, left_out, rms = report.frames_used, len(report.skipped), report.rms_px
    print(f"frames    {used} used, {left_out} skipped; reprojection RMS {rms:.3f} px")
    for skipped in report.skipped:
        print(f"skipped   {skipped.name}: {skipped.why}")
    if report.bearing_deg is None:
        print("bearing   none: no frame carries a compass reading (compass_bearing_deg)")
    else:
        sigma = "" if report.bearing_sigma_deg is None else f" +- {report.bearing_sigma_deg:.1f}"
        print(f"bearing   {report.bearing_deg:.1f}{sigma} deg (compass bearing of the map's +X)")
    print(f"map       '{report.map.name}' written to {out}")


def run_survey_command(args) -> int:
    from pydantic import ValidationError

    from server.ingest import read_fixture
    from server.outcomes import FrameError
    from server.survey.rules import SurveyInputError, SurveyRefused
    from server.survey.run import SurveyFrame, survey
    from shared_schemas.api import NAME_PATTERN

    name = args.name or args.out.stem
    try:
        if not re.match(NAME_PATTERN, name):
            raise BadInput(f"map name '{name}' must match {NAME_PATTERN} (give --name)", field="name")
        sketch = read_map_argument(args.map)
        try:
            labels = _read_labels(args.labels, args.frames)
        except (OSError, ValueError, ValidationError) as error:
            raise BadInput(f"cannot read labels {describe_file_error(args.labels, error)}", field="labels") from None
        frames = []
        for path, frame_labels in zip(args.frames, labels, strict=True):
            try:
                frames.append(SurveyFrame(str(path), read_fixture(path), frame_labels))
            except FrameError as error:
                raise BadInput(f"frame {path}: {error}", field=error.field, error="bad_frame") from None
        try:
            report = survey(frames, sketch, args.anchor, name)
        except SurveyInputError as error:
            raise BadInput(error.message, field=error.field) from None
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    except SurveyRefused as error:
        print(f"refused: {error.message}", file=sys.stderr)
        return EXIT_REFUSED
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(report.map.model_dump_json(by_alias=True, exclude_none=True, indent=2) + "\n")
    if args.json:
        print(report.model_dump_json(by_alias=True, indent=2))
    else:
        _print_report(report, args.out)
    return EXIT_OK
