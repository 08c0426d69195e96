"""`lumipose bench load`: the service under N concurrent clients, on rendered frames of two sizes; its
own fresh server, or a running deployment (`--url`, e.g. the nginx replicas of docker/)."""

from __future__ import annotations

import json
import sys

import httpx
import numpy as np

from lumipose_client.client import Client, LumiposeError
from lumipose_client.crop import crop_frame
from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from shared_schemas import DEMO_MAP_NAME, BeaconMap, FrameMeta, device_profiles
from shared_schemas.cli import BadInput, report_bad_input
from simulator.bench_load import NO_PAGE, LiveLoad, LoadReport, run_load
from simulator.benchmarks import PROFILE_ID, bench_beacon
from simulator.fixtures import fixture_meta
from simulator.local_server import LocalServer
from simulator.render import CameraPose, SensorModel, render_frame

FRAME_WIDTHS = {"1080p": 1080, "full": None, "full-window": None}  # full = the profile's native 3880 x 5184


def service_frame(width: int | None, distance_m: float = 1.0, seed: int = 3) -> tuple[FrameMeta, bytes, BeaconMap]:
    """A rendered test-bench frame `width` pixels wide (native if None), its metadata and map."""
    profile = device_profiles()[PROFILE_ID]
    scale = 1.0 if width is None else width / profile.width
    width, height = round(profile.width * scale), round(profile.height * scale)
    camera = intrinsics_from_profile(profile, width, height)
    pose = CameraPose(position_m=np.array([0.1, -0.15, 0.0]), rotation_wc=rotation_from_ypr(8.0, 2.0, -1.5))
    beacon = bench_beacon(distance_m)
    pixels = render_frame(beacon, camera, pose, width, height, SensorModel(psf_sigma_px=1.0 * scale ** 0.5 + 0.5),
                          np.random.default_rng(seed))
    return fixture_meta(camera, width, height, pose), pixels.tobytes(), BeaconMap(name="load-bench", beacons=[beacon])


def run_service_load(frames: list[str], clients: list[int], seconds: float, encodings: list[str | None],
                     workers: int = 1, url: str | None = None, live: LiveLoad = NO_PAGE) -> list[LoadReport]:
    """Each frame size against its own fresh server, or against the running service at `url` (a
    deployment: its bundled demo map holds the frames' panel); every client count and encoding in turn."""
    if url is not None and live.live_frames is not None:
        raise BadInput("--live-frames is for the server the bench starts, not one at --url", field="live_frames")
    serve_args = ("--workers", str(workers), "--log-level", "warning")
    if live.live_frames is not None:
        serve_args += ("--live-frames", str(live.live_frames))
    reports = []
    for name in frames:
        meta, data, beacon_map = service_frame(FRAME_WIDTHS[name])
        if name.endswith("-window"):  # what a client sends when it cuts the frame to the beacon's window
            meta, data = crop_frame(np.frombuffer(data, np.uint8).reshape(meta.height, meta.width), meta)
        if url is not None:
            reports += _load_runs(url, None, deployment_map(url, beacon_map), name, data, meta, clients, seconds,
                                  encodings, live)
            continue
        with LocalServer(*serve_args) as server:
            map_path = server.data_dir / "maps" / f"{beacon_map.name}.json"
            map_path.parent.mkdir(parents=True, exist_ok=True)
            map_path.write_text(beacon_map.model_dump_json(by_alias=True))
            reports += _load_runs(server.url, server.pid, beacon_map.name, name, data, meta, clients, seconds,
                                  encodings, live)
    return reports


def deployment_map(url: str, beacon_map: BeaconMap) -> str:
    """The name of the map of `url` that holds the load frames' panel: the bundled demo map, which every
    deployment serves (BadInput if that name holds another map there)."""
    with Client(url, timeout_s=30) as client:
        served = client.get_map(DEMO_MAP_NAME)
    if served.beacons != beacon_map.beacons:
        raise BadInput(f"the map '{DEMO_MAP_NAME}' of {url} is not the bundled demo map the load frames were "
                       "rendered for (a stored map of that name hides it)", field="url")
    return DEMO_MAP_NAME


def _load_runs(url: str, server_pid: int | None, map_name: str, name: str, data: bytes, meta: FrameMeta,
               clients: list[int], seconds: float, encodings: list[str | None], live: LiveLoad) -> list[LoadReport]:
    reports = []
    for encoding in encodings:
        for count in clients:
            print(f"{name}, {encoding or 'none'}: {count} client(s) for {seconds:g} s against {url} ...",
                  file=sys.stderr, flush=True)
            reports.append(run_load(url, name, data, meta, clients=count, seconds=seconds, compress=encoding,
                                    server_pid=server_pid, map_name=map_name, live=live))
    return reports


def print_reports(reports: list[LoadReport], as_json: bool) -> None:
    if as_json:
        print(json.dumps([report.as_dict() for report in reports], indent=2))
        return
    print("| frame | body | clients | requests | errors | fixes | req/s | p50 ms | p99 ms | server ms | pipeline ms "
          "| outside pipeline | server CPU ms | peak RSS MB | page |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for r in reports:
        print(f"| {r.frame} | {r.encoding} {r.body_mb:.1f} MB | {r.clients} | {r.requests} | {r.errors} | {r.fixes} "
              f"| {r.throughput_rps:.1f} "
              f"| {r.p50_ms:.1f} | {r.p99_ms:.1f} | {_figure(r.server_request_ms, '.1f')} "
              f"| {_figure(r.server_pipeline_ms, '.1f')} "
              f"| {_figure(_percent(r.outside_pipeline_share), '.0f', ' %')} "
              f"| {_figure(r.server_cpu_ms, '.1f')} | {_figure(r.server_peak_rss_mb, '.0f')} | {_page(r)} |")


def _page(report: LoadReport) -> str:
    """The operator page's part of a run: devices recorded, pictures kept, what the watchers got."""
    if not report.devices and not report.watchers:
        return "-"
    parts = ["devices" if report.devices else "no devices"]
    if report.live_frames is not None:
        parts.append(f"live frames {report.live_frames}")
    if report.watchers:
        parts.append(f"{report.watchers} watcher(s): {report.device_events} + {report.status_events} events "
                     f"{report.event_kb:.0f} kB, {report.pictures} PNG {report.picture_kb:.0f} kB "
                     f"({report.pictures_gone} gone)")
    return ", ".join(parts)


def _percent(share: float | None) -> float | None:
    return None if share is None else 100 * share


def _figure(value: float | None, spec: str, unit: str = "") -> str:
    """A server-side figure, '-' where it was not measured (a deployment's replicas: `--url`)."""
    return "-" if value is None else f"{value:{spec}}{unit}"


def run_load_command(args) -> int:
    """`lumipose bench load` (its flags: simulator/cli.py)."""
    encodings = [None if encoding == "none" else encoding for encoding in args.encodings]
    try:
        if min(args.clients) < 1 or args.seconds <= 0:
            raise BadInput("--clients must be at least 1 and --seconds positive", field="clients")
        if args.watchers < 0 or args.picture_every_s < 0:
            raise BadInput("--watchers and --picture-every-s must not be negative", field="watchers")
        live = LiveLoad(args.devices, args.watchers, args.picture_every_s, args.live_frames)
        reports = run_service_load(args.frames, args.clients, args.seconds, encodings, args.workers, args.url, live)
    except BadInput as problem:
        return report_bad_input(problem, as_json=args.json)
    except (LumiposeError, httpx.HTTPError) as error:
        return report_bad_input(BadInput(f"cannot load-test {args.url}: {error}", field="url"), as_json=args.json)
    print_reports(reports, args.json)
    return 0 if all(report.errors == 0 for report in reports) else 1
