"""Prometheus metrics: requests, latency, fixes and refusal reasons (per worker process)."""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from prometheus_client import CollectorRegistry, Counter, Histogram, disable_created_metrics, generate_latest
from starlette.types import ASGIApp, Receive, Scope, Send

from shared_schemas import LocateResult
from shared_schemas.api import RouteStatus

disable_created_metrics()  # the *_created series only add noise to scrapes

REQUEST_START = "lumipose_request_start"  # `request.state` key: time.perf_counter() when the request came in
LATENCY_BUCKETS_S = (0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0)


class Metrics:
    def __init__(self) -> None:
        self.registry = CollectorRegistry()
        self.requests = Counter("lumipose_requests_total", "HTTP requests", ["route", "status"], registry=self.registry)
        self.latency = Histogram(
            "lumipose_request_seconds",
            "HTTP request latency",
            ["route"],
            buckets=LATENCY_BUCKETS_S,
            registry=self.registry,
        )
        self.fixes = Counter("lumipose_fixes_total", "frames located", registry=self.registry)
        self.no_fix = Counter(
            "lumipose_no_fix_total", "frames without a fix, by reason", ["reason"], registry=self.registry
        )
        self.server_errors = Counter(
            "lumipose_server_errors_total", "requests that ended in a 500 (a bug: logged whole)", registry=self.registry
        )
        self.pipeline = Histogram(
            "lumipose_pipeline_seconds", "pipeline time per frame", buckets=LATENCY_BUCKETS_S, registry=self.registry
        )

    def record_result(self, result: LocateResult) -> None:
        if result.ok:
            self.fixes.inc()
        else:
            self.no_fix.labels(reason=result.reason.value if result.reason else "unknown").inc()
        self.pipeline.observe(result.timing_ms.get("total", 0.0) / 1000.0)

    def outcomes(self) -> tuple[int, dict[str, int]]:
        """Frames located, and frames without a fix by reason, since the start."""
        fixes = sum(s.value for f in self.fixes.collect() for s in f.samples if s.name.endswith("_total"))
        refused = {
            s.labels["reason"]: round(s.value)
            for f in self.no_fix.collect()
            for s in f.samples
            if s.name.endswith("_total")
        }
        return round(fixes), refused

    def exposition(self) -> bytes:
        return generate_latest(self.registry)


class MetricsMiddleware:
    """Counts and times every HTTP request by its route template (not its raw path)."""

    def __init__(self, app: ASGIApp, metrics: Metrics) -> None:
        self.app, self.metrics = app, metrics

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        start, status = time.perf_counter(), 500
        scope.setdefault("state", {})[REQUEST_START] = start  # a route's latency from the request's start

        stream = False  # an event stream's time is how long a page stayed, not a latency

        async def send_and_note(message) -> None:
            nonlocal status, stream
            if message["type"] == "http.response.start":
                status = message["status"]
                stream = any(k == b"content-type" and v.startswith(b"text/event-stream") for k, v in message["headers"])
            await send(message)

        try:
            await self.app(scope, receive, send_and_note)
        finally:
            # a route's template; a mount's path (the page's static files: its root_path); else "unmatched"
            route = getattr(scope.get("route"), "path", None) or scope.get("root_path") or "unmatched"
            self.metrics.requests.labels(route=route, status=str(status)).inc()
            if not stream:
                self.metrics.latency.labels(route=route).observe(time.perf_counter() - start)


@dataclass(frozen=True)
class RouteCounts:
    """One route's counters at one time: requests, 5xx answers, and the latency histogram's cumulative buckets."""

    requests: float = 0.0
    errors: float = 0.0
    buckets: tuple[tuple[float, float], ...] = ()  # (upper bound s, requests at most that long), +inf last

    def minus(self, before: RouteCounts) -> RouteCounts:
        earlier = dict(before.buckets)
        return RouteCounts(
            self.requests - before.requests,
            self.errors - before.errors,
            tuple((bound, count - earlier.get(bound, 0.0)) for bound, count in self.buckets),
        )


def route_counts(metrics: Metrics) -> dict[str, RouteCounts]:
    """Every route's counters now, read from the Prometheus registry."""
    requests: dict[str, float] = {}
    errors: dict[str, float] = {}
    buckets: dict[str, list[tuple[float, float]]] = {}
    for family in metrics.requests.collect():
        for sample in family.samples:
            if sample.name.endswith("_total"):
                route = sample.labels["route"]
                requests[route] = requests.get(route, 0.0) + sample.value
                if sample.labels["status"].startswith("5"):
                    errors[route] = errors.get(route, 0.0) + sample.value
    for family in metrics.latency.collect():
        for sample in family.samples:
            if sample.name.endswith("_bucket"):
                buckets.setdefault(sample.labels["route"], []).append((float(sample.labels["le"]), sample.value))
    return {
        route: RouteCounts(count, errors.get(route, 0.0), tuple(sorted(buckets.get(route, []))))
        for route, count in requests.items()
    }


def histogram_quantile(q: float, buckets: tuple[tuple[float, float], ...]) -> float | None:
    """The q-quantile of a cumulative histogram, linear within its bucket as Prometheus's own
    `histogram_quantile`; the largest finite bound when it falls in the +inf bucket; None when empty."""
    total = buckets[-1][1] if buckets else 0.0
    if total <= 0:
        return None
    rank, lower, below = q * total, 0.0, 0.0
    for bound, count in buckets:
        if count >= rank:
            if math.isinf(bound):
                return lower
            return lower + (bound - lower) * (rank - below) / max(count - below, 1e-12)
        lower, below = bound, count
    return lower


class StatusWindow:
    """The routes' counters of the last `window_s`: samples taken when asked (at most one a second),
    rates and quantiles over the difference between now and the oldest sample within the window.
    Safe to call from many threads at once."""

    def __init__(self, metrics: Metrics, window_s: float = 60.0, clock: Callable[[], float] = time.monotonic) -> None:
        self.metrics, self.window_s, self._clock = metrics, window_s, clock
        self._lock = threading.Lock()
        self._samples: deque[tuple[float, dict[str, RouteCounts]]] = deque([(clock(), {})])  # the start: nothing

    def routes(self) -> tuple[float, list[RouteStatus]]:
        """The window's length and every route's status over it, busiest first."""
        now, counts = self._clock(), route_counts(self.metrics)
        with self._lock:
            if now - self._samples[-1][0] >= 1.0:
                self._samples.append((now, counts))
            while len(self._samples) > 1 and self._samples[1][0] <= now - self.window_s:
                self._samples.popleft()
            then, before = self._samples[0]
        span = max(now - then, 1e-9)
        statuses = []
        for route, total in counts.items():
            recent = total.minus(before.get(route, RouteCounts()))
            quantiles = [histogram_quantile(q, recent.buckets) for q in (0.5, 0.9, 0.99)]
            p50, p90, p99 = (None if v is None else 1000 * v for v in quantiles)
            statuses.append(
                RouteStatus(
                    route=route,
                    requests=round(total.requests),
                    errors=round(total.errors),
                    rate_hz=recent.requests / span,
                    p50_ms=p50,
                    p90_ms=p90,
                    p99_ms=p99,
                )
            )
        return span, sorted(statuses, key=lambda s: (-s.rate_hz, -s.requests, s.route))
