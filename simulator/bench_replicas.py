"""`lumipose bench replicas`: `bench load`'s clients through nginx to one, two, three... replicas sharing Redis
(simulator/replicas.py starts them all on 127.0.0.1), one replica with and without Redis (what the sessions' round
trips add), and the bytes Redis holds per device after an office walk. Figures, not a test.

Every client names its device (`X-Lumipose-Device: load-<n>`), but the frames are the bundled test-bench map's,
which has one beacon: a frame of a one-beacon map needs no session (`server.locator.in_device_session`), so these
runs measure the balancing and the maps' reads from Redis, not the sessions' (`simulator/bench_sessions.py` times
those, in process)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from dataclasses import dataclass

import numpy as np

from lumipose_client.client import Client
from lumipose_client.crop import crop_frame
from simulator.bench_load import LiveLoad, LoadReport, run_load
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures
from simulator.bench_service import FRAME_WIDTHS, deployment_map, service_frame
from simulator.replicas import Replicas

DEVICES = LiveLoad(devices=True)
SERVE_ARGS = ("--log-level", "warning")
WALK = OfficeConfig(walk="zigzag", max_captures=4, pose_scale=0.25, seed=2)
WALK_DEVICE = "walker"


@dataclass(frozen=True)
class Run:
    """One load run and where it went: `replicas` behind nginx, or one replica straight (nginx False)."""

    replicas: int
    redis: bool
    nginx: bool
    load_average_1min: float  # just before the run
    load: LoadReport

    def as_dict(self) -> dict:
        return {"replicas": self.replicas, "redis": self.redis, "nginx": self.nginx,
                "load_average_1min": self.load_average_1min, **self.load.as_dict()}


def _frames(names: list[str]) -> dict[str, tuple]:
    """(meta, bytes) of each load frame, rendered once; the map is the bundled demo map every replica serves."""
    frames = {}
    for name in names:
        meta, data, beacon_map = service_frame(FRAME_WIDTHS[name])
        if name.endswith("-window"):
            meta, data = crop_frame(np.frombuffer(data, np.uint8).reshape(meta.height, meta.width), meta)
        frames[name] = meta, data, beacon_map
    return frames


def _load(url: str, pid: int | None, frames: dict[str, tuple], clients: list[int], seconds: float,
          **where) -> list[Run]:
    runs = []
    for name, (meta, data, beacon_map) in frames.items():
        map_name = deployment_map(url, beacon_map)
        for count in clients:
            print(f"{where}, {name}: {count} client(s) for {seconds:g} s ...", file=sys.stderr, flush=True)
            load_average = os.getloadavg()[0]
            report = run_load(url, name, data, meta, clients=count, seconds=seconds, server_pid=pid,
                              map_name=map_name, live=DEVICES)
            runs.append(Run(load=report, load_average_1min=load_average, **where))
    return runs


def device_bytes(replicas: Replicas) -> dict:
    """An office walk through `replicas`; the device's key in Redis after each burst of ID frames (decoded
    stripes waiting) and after each pose frame (the track): its length and Redis's MEMORY USAGE."""
    assert replicas.redis is not None
    redis = replicas.redis.client()
    beacon_map = office_scenes(WALK)[0].beacon_map()
    sizes: dict[str, list[int]] = {"after_id_frames_strlen": [], "after_id_frames_memory": [],
                                   "after_pose_frame_strlen": [], "after_pose_frame_memory": []}
    with Client(replicas.url) as client:
        client.put_map(beacon_map)
        for capture in walk_captures(WALK):
            for stage, frames in (("id_frames", capture.id_frames), ("pose_frame", (capture.pose_frame,))):
                for frame in frames:
                    client.locate(np.ascontiguousarray(frame.pixels).tobytes(), frame.meta, map=beacon_map.name,
                                  compress=None, device=WALK_DEVICE)
                (key,) = redis.scan_iter(match=f"*{WALK_DEVICE}")
                sizes[f"after_{stage}_strlen"].append(int(redis.strlen(key)))
                sizes[f"after_{stage}_memory"].append(int(redis.memory_usage(key)))
    return {"walk": f"{WALK.walk}, {WALK.max_captures} captures, pose frames at scale {WALK.pose_scale}",
            "key": key.decode(), **sizes}


def _commit() -> str:
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True, text=True,
                              check=True, cwd=os.path.dirname(__file__)).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run_replicas_bench(replica_counts: list[int], frame_names: list[str], clients: list[int],
                       seconds: float) -> dict:
    frames = _frames(frame_names)
    machine = {"cpus": os.cpu_count(), "platform": platform.platform(), "load_average_1min": os.getloadavg()[0]}
    runs: list[Run] = []
    for count in replica_counts:
        with Replicas(count, *SERVE_ARGS) as replicas:
            runs += _load(replicas.url, None, frames, clients, seconds, replicas=count, redis=True, nginx=True)
    for redis in (False, True):  # one replica straight: the sessions in memory, then in Redis
        with Replicas(1, *SERVE_ARGS, redis=redis) as replicas:
            server = replicas.servers[0]
            runs += _load(server.url, server.pid, frames, clients, seconds, replicas=1, redis=redis, nginx=False)
    with Replicas(1, *SERVE_ARGS) as replicas:
        memory = device_bytes(replicas)
    return {"commit": _commit(), "machine": machine, "seconds": seconds, "runs": [run.as_dict() for run in runs],
            "device_bytes": memory}


def print_report(report: dict) -> None:
    runs = report["runs"]
    print(f"commit {report['commit']}, {report['machine']['cpus']} CPUs, load average "
          f"{report['machine']['load_average_1min']:.1f} at the start; {report['seconds']:g} s per run\n")
    print("Through nginx (least_conn), maps in Redis (one-beacon map: no session):\n")
    print("| replicas | frame | clients | requests | errors | req/s | x one replica | p50 ms | p99 ms | load avg |")
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    balanced = [r for r in runs if r["nginx"]]
    one = {(r["frame"], r["clients"]): r["throughput_rps"] for r in balanced if r["replicas"] == 1}
    for r in balanced:
        ratio = r["throughput_rps"] / one[r["frame"], r["clients"]] if (r["frame"], r["clients"]) in one else None
        print(f"| {r['replicas']} | {r['frame']} | {r['clients']} | {r['requests']} | {r['errors']} "
              f"| {r['throughput_rps']:.1f} | {'-' if ratio is None else f'{ratio:.2f}'} | {r['p50_ms']:.1f} "
              f"| {r['p99_ms']:.1f} | {r['load_average_1min']:.1f} |")
    print("\nOne replica straight (no nginx), without and with Redis (its maps; no session):\n")
    print("| frame | clients | req/s memory | req/s Redis | p50 ms memory | p50 ms Redis | p99 ms memory | p99 ms Redis "
          "| server ms memory | server ms Redis |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    straight = [r for r in runs if not r["nginx"]]
    for memory in (r for r in straight if not r["redis"]):
        (redis,) = [r for r in straight if r["redis"] and (r["frame"], r["clients"]) == (memory["frame"],
                                                                                            memory["clients"])]
        print(f"| {memory['frame']} | {memory['clients']} | {memory['throughput_rps']:.1f} "
              f"| {redis['throughput_rps']:.1f} | {memory['p50_ms']:.1f} | {redis['p50_ms']:.1f} "
              f"| {memory['p99_ms']:.1f} | {redis['p99_ms']:.1f} | {memory['server_request_ms']:.1f} "
              f"| {redis['server_request_ms']:.1f} |")
    sizes = report["device_bytes"]
    print(f"\nBytes per device in Redis ({sizes['walk']}; key {sizes['key']}): after the ID frames "
          f"{max(sizes['after_id_frames_strlen'])} B of JSON, MEMORY USAGE {max(sizes['after_id_frames_memory'])} B "
          f"(largest); after a pose frame {max(sizes['after_pose_frame_strlen'])} B, "
          f"{max(sizes['after_pose_frame_memory'])} B")


def run_replicas_command(args) -> int:
    """`lumipose bench replicas` (its flags: simulator/cli.py)."""
    from shared_schemas.cli import BadInput, report_bad_input

    if min(args.replicas) < 1 or min(args.clients) < 1 or args.seconds <= 0:
        return report_bad_input(BadInput("--replicas and --clients must be at least 1 and --seconds positive",
                                         field="replicas"), as_json=args.json)
    report = run_replicas_bench(args.replicas, args.frames, args.clients, args.seconds)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print_report(report)
    return 0 if all(run["errors"] == 0 for run in report["runs"]) else 1
