"""`lumipose client ...`: the service from the command line, through the Python client.

`client locate` prints as `lumipose locate` does (`shared_schemas.captures.print_outcome`).
Exit codes as `lumipose locate`: 0 success (a fix), 1 no fix, 2 a refused request or bad input. Several
photos: one the service refuses (or that cannot be read) is its own line, its error body, and the others go on.
Only the client and the contract are imported here; the figures of `samples evaluate --figures`
come from whoever builds the command line (`lumipose_cli.main` hands in the simulator's).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import httpx
from pydantic import BaseModel

from lumipose_client.client import AnnotatedResult, Client, LumiposeError, read_fixture_files
from shared_schemas import BeaconMap, DeviceProfile, ErrorBody, LocateResult
from shared_schemas.api import Evaluation
from shared_schemas.captures import (
    PHOTO_CAMERA_FLAGS,
    PHOTO_CAMERA_QUERY,
    add_frame_series_arguments,
    all_located,
    annotation_paths,
    bursts_in_upload_order,
    print_outcome,
    write_picture,
)
from shared_schemas.cli import (
    EXIT_BAD_INPUT,
    BadInput,
    check_beacon_id,
    describe_file_error,
    plural,
    read_map_argument,
    reads_environment,
    report_bad_input,
)
from shared_schemas.fixture_files import photo_type

DEFAULT_URL = "http://127.0.0.1:8000"
# `client samples store --label -8,11`: argparse reads an argument that starts with '-' as a flag unless it
# looks like a negative number; a grid cell 'i,j' with a negative i is the common label, so it counts as one.
NEGATIVE_NUMBER_OR_CELL = re.compile(r"^-\d+$|^-\d*\.\d+$|^-\d+,-?\d+$")

# a photo of several that the service refuses for itself (damaged, too large, not a photo): its own line
PHOTO_FAULT_STATUSES = frozenset({400, 413, 415})

MAP_HELP = "a map's name, or a map file (its name is sent: the service must hold that map, see `maps put`)"

Model = TypeVar("Model", bound=BaseModel)
PlotEvaluation = Callable[[Evaluation, Path, float], list[Path]]  # (report, folder, cell m) -> the figures written


def _add_shared_options(parser: argparse.ArgumentParser, top: bool) -> None:
    """--url, --api-key and --json, before the verb (`top`) or after it: `client --url U locate F` and
    `client locate F --url U` both work. Only the top level holds the defaults, so a flag given before
    the verb is not overwritten by a verb's default."""

    def default(value):
        return value if top else argparse.SUPPRESS

    parser.add_argument(
        "--url", default=default(DEFAULT_URL), help=f"service URL (default $LUMIPOSE_URL, else {DEFAULT_URL})"
    )
    parser.add_argument("--api-key", default=default(None), help="for writes (default $LUMIPOSE_API_KEY)")
    parser.add_argument(
        "--json",
        action="store_true",
        default=default(False),
        help="print the service's answer as JSON, and a refusal or bad input as the contract's ErrorBody",
    )


def _verb(actions, name: str, run: Callable[[Client, argparse.Namespace], int], **kwargs) -> argparse.ArgumentParser:
    parser = actions.add_parser(name, **kwargs)
    _add_shared_options(parser, top=False)
    parser.set_defaults(client_run=run)
    return parser


def add_commands(commands, plot_evaluation: PlotEvaluation | None = None) -> None:
    """Add `client ...` to an argparse subparsers object; `samples evaluate --figures` exists when
    `plot_evaluation` is given."""
    # --url and --api-key read LUMIPOSE_URL and LUMIPOSE_API_KEY, on `client` and every verb under it
    client = commands.add_parser("client", help="talk to a running Lumipose service")
    reads_environment(client, frozenset({"--url", "--api-key"}))
    _add_shared_options(client, top=True)
    actions = client.add_subparsers(dest="client_command", required=True)

    locate = _verb(actions, "locate", _locate, help="locate recorded frames or phone photos")
    add_frame_series_arguments(locate)  # sent with X-Lumipose-Device and beacon_id, as the app sends them
    locate.add_argument("--map", help=MAP_HELP + " (default: the service's active map)")
    locate.add_argument("--compress", choices=["gzip", "zstd", "none"], default="gzip", help="upload compression")
    locate.add_argument(
        "--annotate", type=Path, metavar="PNG", help="also write the service's picture (PNG) of what its pipeline saw"
    )
    locate.add_argument(
        "--profile",
        help="a photo's device profile id, bundled or stored on the service (a file: store it first with "
        "`client profiles put`) (default: from its EXIF)",
    )
    locate.add_argument(
        "--camera",
        metavar="FX,FY,CX,CY[,K1,...]",
        help="a photo's intrinsics, pixels of the upright photo (default: none)",
    )

    samples = actions.add_parser("samples", help="recorded samples")
    sample_actions = samples.add_subparsers(dest="samples_command", required=True)
    store = _verb(sample_actions, "store", _store_samples, help="store frames with a label")
    store._negative_number_matcher = NEGATIVE_NUMBER_OR_CELL  # see NEGATIVE_NUMBER_OR_CELL
    store.add_argument("frames", type=Path, nargs="+", help="NAME.json, NAME.y, NAME.yuv or NAME.png")
    store.add_argument("--label", help="for example a grid cell 'i,j' such as -8,11")
    _verb(sample_actions, "list", _list_samples, help="the stored samples")
    delete = _verb(sample_actions, "delete", _delete_samples, help="remove stored samples")
    delete.add_argument("ids", nargs="+", help="sample ids (from `samples list`)")
    evaluate = _verb(sample_actions, "evaluate", _evaluate, help="error and coverage of the stored samples")
    evaluate.add_argument("--map", help=MAP_HELP + ", to re-locate every sample in (default: the active map)")
    evaluate.add_argument("--cell", type=float, default=0.05, help="grid cell side for 'i,j' labels, metres")
    if plot_evaluation is not None:
        evaluate.add_argument(
            "--figures",
            type=Path,
            default=None,
            metavar="DIR",
            help="write the paper's Figs. 13-14 (samples_scatter.png, samples_heatmap.png in "
            "--cell cells) into this folder (default: no figures)",
        )
    evaluate.set_defaults(plot_evaluation=plot_evaluation)

    maps = actions.add_parser("maps", help="beacon maps")
    map_actions = maps.add_subparsers(dest="maps_command", required=True)
    _verb(map_actions, "list", _list_maps, help="the service's maps (* marks the active one)")
    get = _verb(map_actions, "get", _get_map, help="print a map's JSON (to save or edit it)")
    get.add_argument("name", help="the map's name")
    put = _verb(map_actions, "put", _put_map, help="store a map file under its own name")
    put.add_argument("file", type=Path, help="a map file (JSON)")
    activate = _verb(map_actions, "activate", _activate_map, help="make a map the one locate uses by default")
    activate.add_argument("name", help="the map's name")
    delete_map = _verb(map_actions, "delete", _delete_maps, help="remove stored maps (not the active or bundled one)")
    delete_map.add_argument("names", nargs="+", help="the maps' names")

    profiles = actions.add_parser("profiles", help="device profiles (bundled, and stored calibrated ones)")
    profile_actions = profiles.add_subparsers(dest="profiles_command", required=True)
    _verb(profile_actions, "list", _list_profiles, help="the bundled and stored device profiles")
    get_profile = _verb(profile_actions, "get", _get_profile, help="print a profile's JSON (to save or edit it)")
    get_profile.add_argument("id", help="the profile's id (from `profiles list`)")
    put_profile = _verb(profile_actions, "put", _put_profile, help="store a profile file under its own id")
    put_profile.add_argument("file", type=Path, help="a device profile file (JSON), e.g. from `calibrate camera`")
    delete_profile = _verb(profile_actions, "delete", _delete_profiles, help="remove stored profiles")
    delete_profile.add_argument("ids", nargs="+", help="the profiles' ids")
    client.set_defaults(run=_run)


def _run(args) -> int:
    try:
        with Client(args.url, api_key=args.api_key) as client:
            return args.client_run(client, args)
    except LumiposeError as error:
        if args.json:  # the service's own ErrorBody, as it sent it
            return report_bad_input(error.body, as_json=True)
        body = error.body.model_copy(update={"message": f"{error}"})  # with the HTTP status and error code
        return report_bad_input(body)
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    except (OSError, ValueError) as error:  # a file that cannot be read (a pydantic ValidationError is a ValueError)
        return report_bad_input(BadInput(str(error)), as_json=args.json)
    except httpx.HTTPError as error:  # the service is not there
        unreachable = BadInput(f"cannot reach {args.url}: {error}", field="url", error="unreachable")
        return report_bad_input(unreachable, as_json=args.json)


def _served_map_name(client: Client, value: str | None) -> str | None:
    """What `--map` sends: `value`, a map's name; or, when `value` is a map file, the name inside it, once
    the service is seen to hold that very map (else BadInput saying how to store it)."""
    if value is None or not Path(value).is_file():
        return value
    beacon_map = read_map_argument(value)
    store = f"store it with `lumipose client maps put {value}`"
    try:
        served = client.get_map(beacon_map.name)
    except LumiposeError as error:
        if error.status != 404:
            raise
        message = f"the service has no map '{beacon_map.name}' (read from {value}): {store}"
        raise BadInput(message, field="map", error="not_found") from None
    if served != beacon_map:
        message = f"the service's map '{beacon_map.name}' differs from {value}: {store} (it replaces the service's)"
        raise BadInput(message, field="map", error="map_differs")
    return beacon_map.name


def _print(model) -> None:
    print(model.model_dump_json(by_alias=True, indent=2))


def _photo_profile(value: str | None) -> str | None:
    """`--profile` of a photo sent to the service: an id it knows. The API takes no profile body, and a profile
    scales to the photo's size and orientation on the service: a file is refused, not silently ignored."""
    if value is not None and Path(value).is_file():
        raise BadInput(
            f"--profile {value}: the service takes a profile id, not a file; store it first with "
            f"`lumipose client profiles put {value}` and pass its id, or locate the photo locally with "
            f"`lumipose locate PHOTO --profile {value}`",
            field="profile",
        )
    return value


def _locate_photos(
    client: Client, args, photo_types: list[str | None], map_name: str | None, pictures: list[Path | None]
) -> int:
    """Photos, each on its own (a photo has no timestamp or frame kind; `--device` names the session);
    one result each, and with `--annotate` the service's picture of each."""
    if not all(photo_types):
        raise BadInput("give either photos or recorded frames, not both in one call", field="frames")
    profile = _photo_profile(args.profile)
    beacon_map = _printed_map(client, args, map_name)
    several = len(args.frames) > 1
    results, unreadable = [], 0
    for content_type, path, picture in zip(photo_types, args.frames, pictures, strict=True):
        assert content_type is not None  # all() above
        try:
            answer = client.locate_photo(
                path.read_bytes(),
                content_type,
                map=map_name,
                profile=profile,
                camera=args.camera,
                beacon_id=args.beacon_id,
                device=args.device,
                annotate=picture is not None,
            )
        except LumiposeError as error:
            fault = _with_flags(error)
            body = _photo_fault(fault, path, given={"camera": args.camera, "profile": profile})
            if body is None or not several:
                raise fault from None  # the call's fault (a key, a map, the service), or the one photo's
            _print_photo_fault(path, body, args.json)
            unreadable += 1
            continue
        except OSError as error:
            if not several:
                raise
            _print_photo_fault(path, BadInput(f"cannot read {path}: {error}", field="frames").body, args.json)
            unreadable += 1
            continue
        answer = _kept(answer, picture)
        print_outcome(path.name, answer, None, as_json=args.json, several=several, beacon_map=beacon_map)
        results.append(answer)
    if unreadable:
        return EXIT_BAD_INPUT
    return 0 if all(result.ok for result in results) else 1


def _print_photo_fault(path: Path, body: ErrorBody, as_json: bool) -> None:
    """A photo of several the service refused: its line; the JSON body with the file's name before its message
    (the service saw no name)."""
    named = body.model_copy(update={"message": f"{path.name}: {body.message}"}) if as_json else body
    print_outcome(path.name, named, None, as_json=as_json, several=True)


def _with_flags(error: LumiposeError) -> LumiposeError:
    """The service's refusal with the query parameters it asks for (`?profile=ID`) said as this command's flags
    (`--profile ID`): the user of the command line passes those."""
    message = error.body.message
    for query, flag in zip(PHOTO_CAMERA_QUERY, PHOTO_CAMERA_FLAGS, strict=True):
        message = message.replace(query, flag)
    return LumiposeError(error.status, error.body.model_copy(update={"message": message}))


def _kept(answer: LocateResult | AnnotatedResult, picture: Path | None) -> LocateResult:
    """The result of an answer; an annotated one's picture written to `picture` (as `lumipose locate` does)."""
    if isinstance(answer, AnnotatedResult):
        assert picture is not None  # asked for with --annotate
        write_picture(picture, answer.png)
        return answer.result
    return answer


def _printed_map(client: Client, args, map_name: str | None) -> BeaconMap | None:
    """The map located in, for the summary's focal uncertainty at the fix's distance; not fetched for --json."""
    return None if args.json else client.get_map(map_name or client.active_map().name)


def _photo_fault(error: LumiposeError, path: Path, given: dict[str, str | None]) -> ErrorBody | None:
    """The error body of a photo of several that the service could not take (as `lumipose locate` prints a
    frame it cannot read: its line, and the others go on), or None when the fault is the whole call's: one
    naming an option the call `given` (`--camera` is every photo's; without it, field camera is a photo's
    unknown camera)."""
    if error.status not in PHOTO_FAULT_STATUSES or given.get(error.body.field or "") is not None:
        return None
    return error.body


def _print_json(value: list[BaseModel] | dict) -> None:
    """A list of the contract's models, or a plain dict, as JSON."""
    plain = [model.model_dump(mode="json", by_alias=True) for model in value] if isinstance(value, list) else value
    print(json.dumps(plain, indent=2))


def _locate(client: Client, args) -> int:
    """As `lumipose locate` prints: a summary for one frame, one line each for several, in the order used (a
    capture's ID frames, then its pose frame); `--json`: the contract's result (several: one JSON line each).
    `--annotate PNG`: the service's picture of each frame (several: PNG-<frame>.png each)."""
    photos = [photo_type(path) for path in args.frames]
    frames = [] if any(photos) else [read_fixture_files(path) for path in args.frames]
    map_name = _served_map_name(client, args.map)
    try:
        pictures = annotation_paths(args.annotate, args.frames)
        if args.beacon_id is not None:
            check_beacon_id(args.beacon_id, client.get_map(map_name or client.active_map().name))
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    if any(photos):
        return _locate_photos(client, args, photos, map_name, pictures)
    beacon_map = _printed_map(client, args, map_name)
    results: list[LocateResult] = []
    for capture in bursts_in_upload_order([meta.frame_kind for meta, _ in frames]):
        for index in capture:
            meta, data = frames[index]
            answer = client.locate(
                data,
                meta,
                map=map_name,
                beacon_id=args.beacon_id,
                device=args.device,
                compress=None if args.compress == "none" else args.compress,
                annotate=args.annotate is not None,
            )
            result = _kept(answer, pictures[index])
            name = args.frames[index].name
            print_outcome(
                name, result, meta.ground_truth, as_json=args.json, several=len(frames) > 1, beacon_map=beacon_map
            )
            results.append(result)
    return 0 if all_located(results) else 1


def _store_samples(client: Client, args) -> int:
    stored = []
    for path in args.frames:
        meta, data = read_fixture_files(path)
        info = client.store_sample(data, meta, label=args.label)
        stored.append(info)
        if not args.json:
            outcome = "fix" if info.result.ok else f"no fix ({info.result.reason.value})"
            print(f"{info.id}  {path}  label={info.label}  {outcome}")
    if args.json:
        _print_json(stored)
    return 0


def _list_samples(client: Client, args) -> int:
    listed = client.samples()
    if args.json:
        _print(listed)
        return 0
    for info in listed.samples:
        print(
            f"{info.id}  {info.created:%Y-%m-%d %H:%M:%S}  label={info.label}  map={info.map}  "
            f"{'fix' if info.result.ok else info.result.reason.value}"
        )
    return 0


def _delete_samples(client: Client, args) -> int:
    return _delete_each(args.ids, client.delete_sample, "", args.json)


def _evaluate(client: Client, args) -> int:
    report = client.evaluate_samples(map=_served_map_name(client, args.map), cell_m=args.cell)
    figures = args.plot_evaluation(report, args.figures, args.cell) if getattr(args, "figures", None) else []
    if args.json:
        _print(report)
        for figure in figures:  # stdout is the report
            print(f"  figure {figure}", file=sys.stderr)
        return 0
    print(
        f"map {report.map}: {plural(report.samples, 'sample')}, {report.with_truth} with truth, "
        f"coverage {100 * report.coverage:.1f} %"
    )
    if report.mean_mm is not None:
        print(
            f"2D error mm: mean {report.mean_mm:.2f}  std {report.std_mm:.2f}  "
            f"min {report.min_mm:.2f}  max {report.max_mm:.2f}"
        )
    for figure in figures:
        print(f"  figure {figure}")
    return 0


def _read_model(model: type[Model], path: Path) -> Model:
    """A contract model from a JSON file; a ValueError naming the file and the field if it is not one."""
    try:
        return model.model_validate_json(path.read_bytes())
    except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError
        raise ValueError(describe_file_error(path, error)) from None


def _list_maps(client: Client, args) -> int:
    summaries = client.maps()
    if args.json:
        _print_json(summaries)
        return 0
    for summary in summaries:
        active = "*" if summary.active else " "
        print(f"{active} {summary.name}  {plural(summary.beacons, 'beacon')}  ({summary.source})")
    return 0


def _get_map(client: Client, args) -> int:
    _print(client.get_map(args.name))
    return 0


def _put_map(client: Client, args) -> int:
    stored = client.put_map(_read_model(BeaconMap, args.file))
    if args.json:
        _print(stored)
    else:
        print(f"stored map '{stored.name}' ({plural(len(stored.beacons), 'beacon')})")
    return 0


def _activate_map(client: Client, args) -> int:
    active = client.set_active_map(args.name)
    if args.json:
        _print(active)
    else:
        print(f"active map: {active.name}")
    return 0


def _delete_maps(client: Client, args) -> int:
    return _delete_each(args.names, client.delete_map, "map ", args.json)


def _list_profiles(client: Client, args) -> int:
    summaries = client.profiles()
    if args.json:
        _print_json(summaries)
        return 0
    rows = [
        (s.id, f"{s.width}x{s.height}", s.facing.value, "calibrated" if s.calibrated else "datasheet", s.source, s.name)
        for s in summaries
    ]
    widths = [max(len(row[column]) for row in rows) for column in range(5)]
    for row in rows:
        print("  ".join(value.ljust(width) for value, width in zip(row, widths, strict=False)) + f"  {row[5]}")
    return 0


def _get_profile(client: Client, args) -> int:
    _print(client.profile(args.id))
    return 0


def _put_profile(client: Client, args) -> int:
    stored = client.put_profile(_read_model(DeviceProfile, args.file))
    if args.json:
        _print(stored)
    else:
        kind = "calibrated" if stored.intrinsics is not None else "datasheet"
        print(f"stored profile '{stored.id}' ({stored.width}x{stored.height}, {kind})")
    return 0


def _delete_profiles(client: Client, args) -> int:
    return _delete_each(args.ids, client.delete_profile, "profile ", args.json)


def _delete_each(names: list[str], delete: Callable[[str], object], what: str, as_json: bool) -> int:
    """Delete each in turn, saying so; a refusal stops there (LumiposeError). With --json: the names deleted."""
    for name in names:
        delete(name)
        if not as_json:
            print(f"deleted {what}{name}")
    if as_json:
        _print_json({"deleted": names})
    return 0
