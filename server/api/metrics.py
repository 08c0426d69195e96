"""Prometheus metrics: requests, latency, fixes and refusal reasons (per worker process)."""

from __future__ import annotations

import time

from prometheus_client import CollectorRegistry, Counter, Histogram, disable_created_metrics, generate_latest
from starlette.types import ASGIApp, Receive, Scope, Send

from shared_schemas import LocateResult

disable_created_metrics()  # the *_created series only add noise to scrapes

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

        async def send_and_note(message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
            await send(message)

        try:
            await self.app(scope, receive, send_and_note)
        finally:
            route = getattr(scope.get("route"), "path", "unmatched")
            self.metrics.requests.labels(route=route, status=str(status)).inc()
            self.metrics.latency.labels(route=route).observe(time.perf_counter() - start)
