"""Load benchmark: N concurrent clients send one frame for a bounded time; figures, not a test.

Throughput, latency percentiles and errors are measured at the clients; the server's peak
memory from /proc, and the share of its request time spent outside the pipeline from its
own Prometheus sums (request seconds vs pipeline seconds), both over the same run.

`LiveLoad` adds what the operator page brings (issue 16): clients that name their device (the live
board records every frame), open pages subscribed to `/v1/live/events`, and the frame view's pictures.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path

import httpx
import numpy as np

from lumipose_client.client import AsyncClient, EncodedFrame, LumiposeError, encode_frame
from shared_schemas import FrameMeta


@dataclass(frozen=True)
class LiveLoad:
    """What of the operator page a run exercises."""

    devices: bool = False  # client n sends `X-Lumipose-Device: load-<n>`: the live board records its frames
    watchers: int = 0  # open pages: subscribers of /v1/live/events through the run
    picture_every_s: float = 2.0  # one watcher fetches the newest kept picture this often, as the frame view (0: none)
    live_frames: int | None = None  # our own server's `serve --live-frames` (None: its default)


NO_PAGE = LiveLoad()


@dataclass
class _Watched:
    """What the watchers received, and the pictures fetched."""

    events: Counter[str] = field(default_factory=Counter)  # by kind: devices, status, bye
    device_updates: int = 0  # device entries in the `devices` events
    event_bytes: int = 0
    pictures: int = 0
    pictures_gone: int = 0  # 404: no longer kept when asked for
    picture_bytes: int = 0
    newest_seq: int | None = None  # the watched device's newest kept frame
    new_seq: asyncio.Event = field(default_factory=asyncio.Event)


@dataclass(frozen=True)
class LoadReport:
    frame: str
    encoding: str
    body_mb: float  # bytes on the wire per request
    clients: int
    seconds: float
    requests: int
    errors: int
    fixes: int
    throughput_rps: float
    p50_ms: float
    p99_ms: float
    # the server's side: measured on our own server only (a deployment's replicas each count their own)
    server_request_ms: float | None  # mean, from the server's own metrics
    server_pipeline_ms: float | None
    outside_pipeline_share: float | None  # of the server's request time
    server_cpu_ms: float | None  # server process CPU time (user + system) per request
    server_peak_rss_mb: float | None
    # the operator page's part (LiveLoad); the watchers' figures cover the whole time they were subscribed
    devices: bool = False
    live_frames: int | None = None
    watchers: int = 0
    device_events: int = 0
    device_updates: int = 0
    status_events: int = 0
    event_kb: float = 0.0
    pictures: int = 0
    pictures_gone: int = 0
    picture_kb: float = 0.0

    def as_dict(self) -> dict:
        return asdict(self)


def _metric_sum(text: str, name: str, route: str | None = None) -> tuple[float, float]:
    """(sum, count) of a Prometheus histogram, for one route label if given."""
    label = f'{{route="{route}"}}' if route else ""
    total = count = 0.0
    for line in text.splitlines():
        match = re.match(rf"^{name}_(sum|count){re.escape(label)} (\S+)$", line)
        if match:
            total, count = (float(match[2]), count) if match[1] == "sum" else (total, float(match[2]))
    return total, count


def cpu_seconds(pid: int) -> float | None:
    """User + system CPU time of a process so far, from /proc (Linux)."""
    stat = Path(f"/proc/{pid}/stat")
    if not stat.exists():
        return None
    fields = stat.read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def peak_rss_mb(pid: int) -> float | None:
    status = Path(f"/proc/{pid}/status")
    if not status.exists():
        return None
    match = re.search(r"VmHWM:\s+(\d+) kB", status.read_text())
    return int(match[1]) / 1024 if match else None


async def _client_loop(client: AsyncClient, frame: EncodedFrame, meta: FrameMeta, map_name: str | None,
                       device: str | None, stop_at: float, latencies: list[float], outcomes: list[str]) -> None:
    while time.perf_counter() < stop_at:
        start = time.perf_counter()
        try:
            result = await client.locate(frame, meta, map=map_name, device=device)
            outcomes.append("fix" if result.ok else "no_fix")
        except (LumiposeError, httpx.HTTPError) as error:
            outcomes.append(f"error: {error}")
        latencies.append(time.perf_counter() - start)


def _device(client: int, live: LiveLoad) -> str | None:
    return f"load-{client}" if live.devices else None


async def _watch(page: httpx.AsyncClient, watched: _Watched, device: str | None) -> None:
    """Hold /v1/live/events open and read every event, as an open page does (reconnecting after `bye`);
    note `device`'s newest kept frame."""
    while True:
        async with page.stream("GET", "/v1/live/events") as response:
            response.raise_for_status()
            kind = ""
            try:
                async for line in response.aiter_lines():
                    if line.startswith("event: "):
                        kind = line.removeprefix("event: ")
                        watched.events[kind] += 1
                    elif line.startswith("data: ") and kind == "devices":
                        _read_devices(json.loads(line.removeprefix("data: "))["devices"], watched, device)
            finally:
                watched.event_bytes += response.num_bytes_downloaded


def _read_devices(devices: list[dict], watched: _Watched, device: str | None) -> None:
    watched.device_updates += len(devices)
    for live in devices:
        if live["device"] == device and live["frames_kept"] and live["frames_kept"][-1] != watched.newest_seq:
            watched.newest_seq = live["frames_kept"][-1]
            watched.new_seq.set()


async def _fetch_pictures(page: httpx.AsyncClient, watched: _Watched, device: str, every_s: float) -> None:
    """The frame view: the newest kept picture of `device` as soon as an event names it, then at most every
    `every_s` (a 404 when the frame is no longer kept, as a page can get too)."""
    while True:
        await watched.new_seq.wait()
        watched.new_seq.clear()
        response = await page.get(f"/v1/live/devices/{device}/frames/{watched.newest_seq}.png")
        if response.status_code == 404:
            watched.pictures_gone += 1
        else:
            response.raise_for_status()
            watched.pictures += 1
            watched.picture_bytes += len(response.content)
        await asyncio.sleep(every_s)


def _page_tasks(page: httpx.AsyncClient, watched: _Watched, live: LiveLoad) -> list[asyncio.Task]:
    device = _device(0, live)
    tasks = [asyncio.create_task(_watch(page, watched, device)) for _ in range(live.watchers)]
    if live.watchers and live.picture_every_s > 0 and device is not None:
        tasks.append(asyncio.create_task(_fetch_pictures(page, watched, device, live.picture_every_s)))
    return tasks


async def _subscribed(watched: _Watched, tasks: list[asyncio.Task], watchers: int, timeout_s: float = 30) -> None:
    """Until every watcher has its first event (a failed subscription raises here)."""
    deadline = time.perf_counter() + timeout_s
    while watched.events["devices"] < watchers:
        for task in tasks:
            if task.done():
                task.result()
        if time.perf_counter() > deadline:
            raise TimeoutError(f"the watchers got no first event from /v1/live/events in {timeout_s:g} s")
        await asyncio.sleep(0.01)


async def _run(url: str, frame: EncodedFrame, meta: FrameMeta, clients: int, seconds: float,
               map_name: str | None, metrics: bool, live: LiveLoad, watched: _Watched):
    latencies: list[float] = []
    outcomes: list[str] = []
    async with AsyncClient(url, timeout_s=120) as client, httpx.AsyncClient(base_url=url, timeout=30) as page:
        tasks = _page_tasks(page, watched, live)
        try:
            await _subscribed(watched, tasks, live.watchers)
            await client.locate(frame, meta, map=map_name, device=_device(0, live))  # warm-up, not counted
            before = httpx.get(f"{url}/metrics").text if metrics else ""
            stop_at = time.perf_counter() + seconds
            started = time.perf_counter()
            await asyncio.gather(*(_client_loop(client, frame, meta, map_name, _device(n, live), stop_at,
                                                latencies, outcomes) for n in range(clients)))
            elapsed = time.perf_counter() - started
            after = httpx.get(f"{url}/metrics").text if metrics else ""
        finally:
            for task in tasks:
                task.cancel()
            failures = [r for r in await asyncio.gather(*tasks, return_exceptions=True)
                        if not isinstance(r, asyncio.CancelledError)]
        if failures:
            raise failures[0]
    return latencies, outcomes, elapsed, before, after


def run_load(url: str, name: str, data: bytes, meta: FrameMeta, *, clients: int, seconds: float,
             compress: str | None = None, server_pid: int | None = None, map_name: str | None = None,
             live: LiveLoad = NO_PAGE) -> LoadReport:
    frame = encode_frame(data, compress)  # encoded once: the client's cost is not measured
    watched = _Watched()
    cpu_before = cpu_seconds(server_pid) if server_pid else None
    latencies, outcomes, elapsed, before, after = asyncio.run(
        _run(url, frame, meta, clients, seconds, map_name, server_pid is not None, live, watched))
    cpu_after = cpu_seconds(server_pid) if server_pid else None
    deltas = [np.subtract(_metric_sum(after, metric, route), _metric_sum(before, metric, route))
              for metric, route in (("lumipose_request_seconds", "/v1/locate"), ("lumipose_pipeline_seconds", None))]
    (request_s, request_n), (pipeline_s, pipeline_n) = deltas
    latency_ms = 1000 * np.array(latencies)
    return LoadReport(
        frame=name, encoding=compress or "none", body_mb=len(frame.data) / 1e6, clients=clients,
        seconds=round(elapsed, 2), requests=len(outcomes),
        errors=sum(outcome.startswith("error") for outcome in outcomes),
        fixes=outcomes.count("fix"), throughput_rps=len(outcomes) / elapsed,
        p50_ms=float(np.percentile(latency_ms, 50)), p99_ms=float(np.percentile(latency_ms, 99)),
        server_request_ms=1000 * request_s / max(request_n, 1) if server_pid else None,
        server_pipeline_ms=1000 * pipeline_s / max(pipeline_n, 1) if server_pid else None,
        outside_pipeline_share=(1 - pipeline_s / request_s if request_s else float("nan")) if server_pid else None,
        server_cpu_ms=(1000 * (cpu_after - cpu_before) / (len(outcomes) + 1)  # + the warm-up request
                       if cpu_before is not None and cpu_after is not None else None),
        server_peak_rss_mb=peak_rss_mb(server_pid) if server_pid else None,
        devices=live.devices, live_frames=live.live_frames, watchers=live.watchers,
        device_events=watched.events["devices"], device_updates=watched.device_updates,
        status_events=watched.events["status"], event_kb=watched.event_bytes / 1e3,
        pictures=watched.pictures, pictures_gone=watched.pictures_gone, picture_kb=watched.picture_bytes / 1e3,
    )
