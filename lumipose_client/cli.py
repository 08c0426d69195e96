"""`lumipose client ...`: the service from the command line, through the Python client.

Exit codes as `lumipose locate`: 0 success (a fix), 1 no fix, 2 a refused request or bad input.
Only the client and the contract are imported here; the figures of `samples evaluate --figures`
come from whoever builds the command line (`lumipose_cli.main` hands in the simulator's).
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from pathlib import Path

from lumipose_client.client import Client, LumiposeError, read_fixture_files
from shared_schemas import BeaconMap, DeviceProfile
from shared_schemas.api import Evaluation

DEFAULT_URL = os.environ.get("LUMIPOSE_URL", "http://127.0.0.1:8000")

PlotEvaluation = Callable[[Evaluation, Path, float], list[Path]]  # (report, folder, cell m) -> the figures written


def add_commands(commands, plot_evaluation: PlotEvaluation | None = None) -> None:
    """Add `client ...` to an argparse subparsers object; `samples evaluate --figures` exists when
    `plot_evaluation` is given."""
    client = commands.add_parser("client", help="talk to a running Lumipose service")
    client.add_argument("--url", default=DEFAULT_URL, help="service URL (default $LUMIPOSE_URL or %(default)s)")
    client.add_argument("--api-key", default=os.environ.get("LUMIPOSE_API_KEY"), help="default $LUMIPOSE_API_KEY")
    actions = client.add_subparsers(dest="client_command", required=True)

    locate = actions.add_parser("locate", help="locate one recorded frame")
    locate.add_argument("frame", type=Path, help="NAME.json, NAME.y, NAME.yuv or NAME.png")
    locate.add_argument("--map", help="map name (default: the active map)")
    locate.add_argument("--compress", choices=["gzip", "zstd", "none"], default="gzip", help="default gzip")
    locate.set_defaults(client_run=_locate)

    samples = actions.add_parser("samples", help="recorded samples")
    sample_actions = samples.add_subparsers(dest="samples_command", required=True)
    store = sample_actions.add_parser("store", help="store frames with a label")
    store.add_argument("frames", type=Path, nargs="+")
    store.add_argument("--label", help="for example a grid cell 'i,j'")
    store.set_defaults(client_run=_store_samples)
    sample_actions.add_parser("list").set_defaults(client_run=_list_samples)
    delete = sample_actions.add_parser("delete")
    delete.add_argument("ids", nargs="+")
    delete.set_defaults(client_run=_delete_samples)
    evaluate = sample_actions.add_parser("evaluate", help="error and coverage of the stored samples")
    evaluate.add_argument("--map")
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
    evaluate.set_defaults(client_run=_evaluate, plot_evaluation=plot_evaluation)

    maps = actions.add_parser("maps", help="beacon maps")
    map_actions = maps.add_subparsers(dest="maps_command", required=True)
    map_actions.add_parser("list").set_defaults(client_run=_list_maps)
    get = map_actions.add_parser("get")
    get.add_argument("name")
    get.set_defaults(client_run=_get_map)
    put = map_actions.add_parser("put", help="store a map file under its own name")
    put.add_argument("file", type=Path)
    put.set_defaults(client_run=_put_map)
    activate = map_actions.add_parser("activate")
    activate.add_argument("name")
    activate.set_defaults(client_run=_activate_map)

    profiles = actions.add_parser("profiles", help="device profiles (bundled, and stored calibrated ones)")
    profile_actions = profiles.add_subparsers(dest="profiles_command", required=True)
    profile_actions.add_parser("list").set_defaults(client_run=_list_profiles)
    get_profile = profile_actions.add_parser("get")
    get_profile.add_argument("id")
    get_profile.set_defaults(client_run=_get_profile)
    put_profile = profile_actions.add_parser("put", help="store a profile file under its own id")
    put_profile.add_argument("file", type=Path)
    put_profile.set_defaults(client_run=_put_profile)
    delete_profile = profile_actions.add_parser("delete", help="remove stored profiles")
    delete_profile.add_argument("ids", nargs="+")
    delete_profile.set_defaults(client_run=_delete_profiles)
    client.set_defaults(run=_run)


def _run(args) -> int:
    try:
        with Client(args.url, api_key=args.api_key) as client:
            return args.client_run(client, args)
    except LumiposeError as error:
        print(f"error: {error}" + (f" (field {error.body.field})" if error.body.field else ""), file=sys.stderr)
    except (OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
    except Exception as error:  # httpx transport errors: the service is not there
        print(f"error: cannot reach {args.url}: {error}", file=sys.stderr)
    return 2


def _print(model) -> None:
    print(model.model_dump_json(by_alias=True, indent=2))


def _locate(client: Client, args) -> int:
    result = client.locate_fixture(
        args.frame, map=args.map, compress=None if args.compress == "none" else args.compress
    )
    _print(result)
    return 0 if result.ok else 1


def _store_samples(client: Client, args) -> int:
    for path in args.frames:
        meta, data = read_fixture_files(path)
        info = client.store_sample(data, meta, label=args.label)
        outcome = "fix" if info.result.ok else f"no fix ({info.result.reason.value})"
        print(f"{info.id}  {path}  label={info.label}  {outcome}")
    return 0


def _list_samples(client: Client, args) -> int:
    for info in client.samples().samples:
        print(
            f"{info.id}  {info.created:%Y-%m-%d %H:%M:%S}  label={info.label}  map={info.map}  "
            f"{'fix' if info.result.ok else info.result.reason.value}"
        )
    return 0


def _delete_samples(client: Client, args) -> int:
    for sample_id in args.ids:
        client.delete_sample(sample_id)
        print(f"deleted {sample_id}")
    return 0


def _evaluate(client: Client, args) -> int:
    report = client.evaluate_samples(map=args.map, cell_m=args.cell)
    print(
        f"map {report.map}: {report.samples} samples, {report.with_truth} with truth, "
        f"coverage {100 * report.coverage:.1f} %"
    )
    if report.mean_mm is not None:
        print(
            f"2D error mm: mean {report.mean_mm:.2f}  std {report.std_mm:.2f}  "
            f"min {report.min_mm:.2f}  max {report.max_mm:.2f}"
        )
    if getattr(args, "figures", None):
        for path in args.plot_evaluation(report, args.figures, args.cell):
            print(f"  figure {path}")
    return 0


def _list_maps(client: Client, args) -> int:
    for summary in client.maps():
        print(f"{'*' if summary.active else ' '} {summary.name}  {summary.beacons} beacons  ({summary.source})")
    return 0


def _get_map(client: Client, args) -> int:
    _print(client.get_map(args.name))
    return 0


def _put_map(client: Client, args) -> int:
    stored = client.put_map(BeaconMap.model_validate(json.loads(args.file.read_text())))
    print(f"stored map '{stored.name}' ({len(stored.beacons)} beacons)")
    return 0


def _activate_map(client: Client, args) -> int:
    print(f"active map: {client.set_active_map(args.name).name}")
    return 0


def _list_profiles(client: Client, args) -> int:
    for summary in client.profiles():
        kind = "calibrated" if summary.calibrated else "datasheet"
        print(f"{summary.id}  {summary.width}x{summary.height}  {summary.facing.value}  {kind}  ({summary.source})")
    return 0


def _get_profile(client: Client, args) -> int:
    _print(client.profile(args.id))
    return 0


def _put_profile(client: Client, args) -> int:
    stored = client.put_profile(DeviceProfile.model_validate_json(args.file.read_bytes()))
    kind = "calibrated" if stored.intrinsics is not None else "datasheet"
    print(f"stored profile '{stored.id}' ({stored.width}x{stored.height}, {kind})")
    return 0


def _delete_profiles(client: Client, args) -> int:
    for profile_id in args.ids:
        client.delete_profile(profile_id)
        print(f"deleted profile {profile_id}")
    return 0
