"""What keeping device sessions in Redis costs, in process: the time Redis adds to each frame and the bytes a
device holds there.

    redis-server --port 6390 --save "" --appendonly no &
    python -m simulator.bench_sessions --redis redis://127.0.0.1:6390/0 [--captures 30] [--devices 8] [--json]

The office walk's frames (ID frames, then the pose frame, as the app sends them) go through `Devices`
(memory) and `SharedDevices` (Redis) for several devices in turn. Added time is a frame's time in
`SharedDevices.locate` minus its time in `locate_in_record` (the work both stores do), split into the
record's JSON both ways (`load_device`, `dump_device`) and the rest: the round trips (WATCH, GET,
MULTI/SET/EXEC) and the client's own work. Bytes: STRLEN and MEMORY USAGE of the
device's key after each frame.
"""

from __future__ import annotations

import argparse
import json
import time
import uuid
from typing import Any

import numpy as np

from server.redis_store import connect
from server.tracking import shared
from server.tracking.devices import Devices
from server.tracking.shared import SharedDevices
from server.vlc.capture import is_id_frame
from simulator.bench_office import OfficeConfig, office_scenes, walk_captures


def _percentiles(values: list[float]) -> dict[str, float]:
    return {"p50": float(np.percentile(values, 50)), "p99": float(np.percentile(values, 99)), "n": len(values)}


class _Timed:
    """Replaces `server.tracking.shared.<name>` by itself while in use, adding up the time spent in it."""

    def __init__(self, name: str):
        self.name, self.total_s = name, 0.0
        self._original = getattr(shared, name)

    def __call__(self, *args):
        started = time.perf_counter()
        try:
            return self._original(*args)
        finally:
            self.total_s += time.perf_counter() - started

    def __enter__(self) -> _Timed:
        setattr(shared, self.name, self)
        return self

    def __exit__(self, *exc) -> None:
        setattr(shared, self.name, self._original)


def measure(redis_url: str, captures: int, devices: int) -> dict[str, Any]:
    config = OfficeConfig(walk="zigzag", max_captures=captures, pose_scale=0.25, seed=3)
    beacon_map = office_scenes(config)[0].beacon_map()
    frames = [f for c in walk_captures(config) for f in (*c.id_frames, c.pose_frame)]
    memory, stored = Devices(), SharedDevices.from_url(redis_url, prefix=f"bench-{uuid.uuid4().hex[:8]}:")
    client = connect(redis_url)
    parts = ("memory", "redis", "added", "json", "round_trips")
    times: dict[str, dict[str, list[float]]] = {kind: {p: [] for p in parts} for kind in ("pose", "id")}
    strlen: list[int] = []
    usage: list[int] = []
    with _Timed("locate_in_record") as work, _Timed("load_device") as load, _Timed("dump_device") as dump:
        for device in (f"phone-{k}" for k in range(devices)):
            for frame in frames:
                by = times["id" if is_id_frame(frame) else "pose"]
                started = time.perf_counter()
                memory.locate(device, frame, beacon_map)
                by["memory"].append(time.perf_counter() - started)
                work.total_s = load.total_s = dump.total_s = 0.0
                started = time.perf_counter()
                stored.locate(device, frame, beacon_map)
                added_s = time.perf_counter() - started - work.total_s
                by["redis"].append(time.perf_counter() - started)
                by["added"].append(added_s)
                by["json"].append(load.total_s + dump.total_s)
                by["round_trips"].append(added_s - load.total_s - dump.total_s)
                strlen.append(int(client.strlen(stored.key(device))))
                usage.append(int(client.memory_usage(stored.key(device)) or 0))
    ms = {kind: {name: _percentiles([1000 * t for t in values]) for name, values in by.items()}
          for kind, by in times.items()}
    return {
        "frames_ms": ms,
        "record_bytes": {"strlen": _percentiles(strlen) | {"max": max(strlen)},
                         "memory_usage": _percentiles(usage) | {"max": max(usage)}},
        "conflicts": stored.conflicts,
        "redis": str(client.info("server")["redis_version"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--redis", required=True, help="the Redis URL to measure against (redis://host:port/db)")
    parser.add_argument("--captures", type=int, default=30, help="captures of the office walk (default 30)")
    parser.add_argument("--devices", type=int, default=8, help="devices walking it in turn (default 8)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    figures = measure(args.redis, args.captures, args.devices)
    if args.json:
        print(json.dumps(figures, indent=1))
        return
    for kind, by in figures["frames_ms"].items():
        for name, p in by.items():
            print(f"{kind:4} frame {name:11} p50 {p['p50']:7.2f} ms  p99 {p['p99']:7.2f} ms  ({p['n']} frames)")
    for name, p in figures["record_bytes"].items():
        print(f"record {name:12} p50 {p['p50']:9.0f} B  p99 {p['p99']:9.0f} B  max {p['max']} B")
    print(f"conflicts {figures['conflicts']}; Redis {figures['redis']}")


if __name__ == "__main__":
    main()
