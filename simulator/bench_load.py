"""Load benchmark: N concurrent clients send one frame for a bounded time; figures, not a test.

Throughput, latency percentiles and errors are measured at the clients; the server's peak
memory from /proc, and the share of its request time spent outside the pipeline from its
own Prometheus sums (request seconds vs pipeline seconds), both over the same run.
"""

from __future__ import annotations

import asyncio
import os
import re
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import httpx
import numpy as np

from lumipose_client.client import AsyncClient, EncodedFrame, LumiposeError, encode_frame
from shared_schemas import FrameMeta


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
                       stop_at: float, latencies: list[float], outcomes: list[str]) -> None:
    while time.perf_counter() < stop_at:
        start = time.perf_counter()
        try:
            result = await client.locate(frame, meta, map=map_name)
            outcomes.append("fix" if result.ok else "no_fix")
        except (LumiposeError, httpx.HTTPError) as error:
            outcomes.append(f"error: {error}")
        latencies.append(time.perf_counter() - start)


async def _run(url: str, frame: EncodedFrame, meta: FrameMeta, clients: int, seconds: float,
               map_name: str | None, metrics: bool):
    latencies: list[float] = []
    outcomes: list[str] = []
    async with AsyncClient(url, timeout_s=120) as client:
        await client.locate(frame, meta, map=map_name)  # warm-up, not counted
        before = httpx.get(f"{url}/metrics").text if metrics else ""
        stop_at = time.perf_counter() + seconds
        started = time.perf_counter()
        await asyncio.gather(*(_client_loop(client, frame, meta, map_name, stop_at, latencies, outcomes)
                               for _ in range(clients)))
        elapsed = time.perf_counter() - started
        after = httpx.get(f"{url}/metrics").text if metrics else ""
    return latencies, outcomes, elapsed, before, after


def run_load(url: str, name: str, data: bytes, meta: FrameMeta, *, clients: int, seconds: float,
             compress: str | None = None, server_pid: int | None = None, map_name: str | None = None) -> LoadReport:
    frame = encode_frame(data, compress)  # encoded once: the client's cost is not measured
    cpu_before = cpu_seconds(server_pid) if server_pid else None
    latencies, outcomes, elapsed, before, after = asyncio.run(
        _run(url, frame, meta, clients, seconds, map_name, metrics=server_pid is not None))
    cpu_after = cpu_seconds(server_pid) if server_pid else None
    deltas = [np.subtract(_metric_sum(after, metric, route), _metric_sum(before, metric, route))
              for metric, route in (("lumipose_request_seconds", "/v1/locate"), ("lumipose_pipeline_seconds", None))]
    (request_s, request_n), (pipeline_s, pipeline_n) = deltas
    latency_ms = 1000 * np.array(latencies)
    return LoadReport(
        frame=name, encoding=compress or "none", body_mb=len(frame.data) / 1e6, clients=clients, seconds=round(elapsed, 2), requests=len(outcomes),
        errors=sum(outcome.startswith("error") for outcome in outcomes),
        fixes=outcomes.count("fix"), throughput_rps=len(outcomes) / elapsed,
        p50_ms=float(np.percentile(latency_ms, 50)), p99_ms=float(np.percentile(latency_ms, 99)),
        server_request_ms=1000 * request_s / max(request_n, 1) if server_pid else None,
        server_pipeline_ms=1000 * pipeline_s / max(pipeline_n, 1) if server_pid else None,
        outside_pipeline_share=(1 - pipeline_s / request_s if request_s else float("nan")) if server_pid else None,
        server_cpu_ms=(1000 * (cpu_after - cpu_before) / (len(outcomes) + 1)  # + the warm-up request
                       if cpu_before is not None and cpu_after is not None else None),
        server_peak_rss_mb=peak_rss_mb(server_pid) if server_pid else None,
    )
